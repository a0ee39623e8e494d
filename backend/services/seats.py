"""A class's seats as the gateway keeps them: each seat's progress in the exercise of the
lesson plan it is at (it survives rebuilds of the seat's machine and restarts of the
service), and the class itself: its plan, its seats, its machine template."""

from __future__ import annotations

import json
from dataclasses import dataclass, field

from api.classes import AnswerGiven, ClassResumed, RaisedHand, StageResult
from api.faults import FaultInfo
from api.machines import MachineLists
from backend.services import findings
from backend.services.audit_log import Entry
from backend.services.auth import Actor
from backend.services.store import StoredChange, parameter_entry
from nc_sim.config import MachineConfig
from nc_sim.training.exercise import Exercise
from nc_sim.training.variation import seat_seed


@dataclass
class Seat:
    """One seat's progress (the gateway's: it survives rebuilds of the seat's machine)."""

    class_id: str
    n: int
    student: str
    user: str
    machine: str
    exercise: Exercise  # the one it is at, with the seat's own numbers
    stage: int = 0  # its place in the lesson plan
    values: dict[str, float] = field(default_factory=dict)  # the seat's numbers in it
    done: list[StageResult] = field(default_factory=list)  # the exercises moved on from
    hints: set[int] = field(default_factory=set)
    first_passed_s: dict[str, float] = field(default_factory=dict)  # check id -> seat time
    passed: dict[str, bool] = field(default_factory=dict)  # holds now
    detail: dict[str, str] = field(default_factory=dict)
    first_detail: dict[str, str] = field(default_factory=dict)  # this build's first words
    time_base_s: float = 0.0  # seat time of the machine's earlier builds
    epoch: int = 0
    epoch_start_s: float | None = None  # machine time the current build was first seen at
    last_t_s: float = 0.0
    frozen: bool = False
    joined_unix: float | None = None  # the student's first login: seat time runs from there
    hand: RaisedHand | None = None  # the student asks for help
    faults: list[FaultInfo] = field(default_factory=list)  # as they stood at the class's end
    answers: findings.Answers = field(default_factory=dict)  # to the finding checks

    @property
    def seat_time_s(self) -> float:
        return self.time_base_s + self.last_t_s - (self.epoch_start_s or 0.0)

    def progress_json(self) -> str:
        return json.dumps(
            {
                "hints": sorted(self.hints),
                "first_passed_s": self.first_passed_s,
                "passed": self.passed,
                "detail": self.detail,
                "seat_time_s": self.seat_time_s,
                "frozen": self.frozen,
                "joined_unix": self.joined_unix,
                "hand": self.hand.model_dump() if self.hand else None,
                "faults": [f.model_dump(mode="json") for f in self.faults],
                "answers": {
                    k: [a.model_dump(mode="json") for a in given]
                    for k, given in self.answers.items()
                },
                "stage": self.stage,
                "values": self.values,
                "done": [d.model_dump(mode="json") for d in self.done],
            }
        )

    def load_progress(self, text: str, plan: list[Exercise]) -> None:
        """Its progress as saved; its exercise from `plan` with its numbers."""
        p = json.loads(text)
        self.stage = min(int(p.get("stage", 0)), len(plan) - 1)
        self.values = {k: float(v) for k, v in p.get("values", {}).items()}
        self.exercise = plan[self.stage].with_values(self.values)
        self.done = [StageResult.model_validate(d) for d in p.get("done", [])]
        self.hints = set(p.get("hints", []))
        self.first_passed_s = dict(p.get("first_passed_s", {}))
        self.passed = dict(p.get("passed", {}))
        self.detail = dict(p.get("detail", {}))
        self.time_base_s = float(p.get("seat_time_s", 0.0))
        self.frozen = bool(p.get("frozen", False))
        self.joined_unix = p.get("joined_unix")
        self.hand = RaisedHand.model_validate(p["hand"]) if p.get("hand") else None
        self.faults = [FaultInfo.model_validate(f) for f in p.get("faults", [])]
        self.answers = {
            k: [AnswerGiven.model_validate(a) for a in given]
            for k, given in p.get("answers", {}).items()
        }


@dataclass
class Class:
    id: str
    title: str
    plan: list[Exercise]  # the lesson plan, each exercise as its file says
    plan_texts: list[str]  # the files
    instructor: str
    created_unix: float
    ended_unix: float | None
    seats: list[Seat]
    lists: MachineLists | None = None  # the seats' machine template; None: the demo lathe
    resumed: ClassResumed | None = None  # built again by a restart of the service
    presenting: str | None = None  # a machine every seat watches, read-only
    _machines: dict[tuple[int, int], MachineConfig] = field(default_factory=dict)

    def seat_machine(self, seat: Seat) -> MachineConfig:
        """A seat's machine as its exercise starts it (what its findings are graded on)."""
        key = (seat.n, seat.stage)
        if key not in self._machines:
            self._machines[key] = findings.seat_machine(seat.exercise, self.lists)
        return self._machines[key]

    def enter(self, seat: Seat, stage: int) -> None:
        """The seat is at the plan's exercise `stage`, with its own numbers in it."""
        ex = self.plan[stage]
        seat.stage = stage
        seat.exercise, seat.values = ex.for_seat(seat_seed(self.id, ex.id), seat.n)


def seat_name(class_id: str, n: int) -> str:
    """A seat's login and machine id: `<class>-s01`."""
    return f"{class_id}-s{n:02d}"


def start_values(actor: Actor, mid: str, ex: Exercise) -> tuple[list[StoredChange], list[Entry]]:
    """An exercise's starting values as stored changes, each with its audit row."""
    changes = [
        StoredChange(v.scope.value, v.target, v.name, None, v.value, "now") for v in ex.start
    ]
    why = f"exercise '{ex.id}' starts so"
    return changes, [parameter_entry(mid, actor.name, actor.session, ch, why) for ch in changes]
