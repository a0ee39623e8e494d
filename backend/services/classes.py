"""Classes: an instructor's class of seats, each a student's login and a machine of its own
built from the exercise it is at (its starting values, its faults with this seat's own
numbers, its checks evaluated by the machine's worker). A class runs a lesson plan: its
exercises in order, each seat moving on by itself (its student, once every check passed) or
by the instructor; each exercise has its own clock and score.

The seats' progress lives here: a check counts from the seat time it first held (the time
weighting of the score), hints taken cost points. Seat time is the simulated time the seat's
machine ran in its exercise, summed over its builds (a restart starts the machine's clock
again, not the seat's). A class that ends takes its machines and logins away; its record, the seats'
results and injected faults, their traces and the audit stay for the debrief. A student's
session that the end took away still names their seat, so their page can show the result.
"""

from __future__ import annotations

import json
import threading
import time
from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait

from api.auth import ALLOWED, Action, Role
from api.classes import (
    AnswerGiven,
    CheckState,
    ClassCreate,
    ClassCreated,
    ClassInfo,
    ClassResumed,
    FindingAnswer,
    HandRequest,
    RaisedHand,
    SeatFaults,
    SeatInfo,
    SeatLink,
    SeatResult,
    StageResult,
)
from api.faults import FaultInfo, FaultInject
from api.machines import MachineCreate, MachineLists
from backend.errors import ApiError, Conflict, Forbidden, Invalid, not_found
from backend.services import findings, training
from backend.services.accounts import Accounts, digest
from backend.services.audit import Audit
from backend.services.audit_log import Entry
from backend.services.auth import Actor
from backend.services.exercises import Exercises
from backend.services.machines import MachineProxy, MachineService, lists_rejected
from backend.services.seats import Class, Seat, seat_name, start_values
from backend.services.store import Store
from backend.workers.protocol import Pace
from nc_sim.config import machine_from_lists
from nc_sim.errors import NcUsageError
from nc_sim.params import ParamListError
from nc_sim.training.checks import CheckResult
from nc_sim.training.exercise import Exercise, ExerciseError, parse_exercise
from nc_sim.training.score import score as exercise_score
from nc_sim.training.template import check_fits

SCHEMA = """
CREATE TABLE IF NOT EXISTS classes (  -- backend/services/classes.py
    id TEXT PRIMARY KEY,
    title TEXT NOT NULL,
    exercise TEXT NOT NULL,
    exercise_text TEXT NOT NULL,   -- the exercise file as the class ran it
    instructor TEXT NOT NULL,
    created REAL NOT NULL,
    ended REAL
);
CREATE TABLE IF NOT EXISTS seats (
    class TEXT NOT NULL,
    n INTEGER NOT NULL,
    student TEXT NOT NULL,
    user TEXT NOT NULL,
    machine TEXT NOT NULL,
    progress TEXT NOT NULL,        -- JSON: hints taken, checks' first pass and detail, time,
                                   -- faults (kept at the end)
    PRIMARY KEY (class, n)
);
CREATE TABLE IF NOT EXISTS ended_sessions (  -- a seat's sessions the class's end took away
    digest TEXT PRIMARY KEY,       -- SHA-256 of the session id (as the sessions table)
    class TEXT NOT NULL,
    n INTEGER NOT NULL,
    expires REAL NOT NULL          -- the session's own expiry: its result shows until then
);
CREATE TABLE IF NOT EXISTS class_plan (  -- a class's lesson plan (none: classes.exercise alone)
    class TEXT NOT NULL,
    k INTEGER NOT NULL,            -- its place in the plan, from 0
    exercise TEXT NOT NULL,
    text TEXT NOT NULL,            -- the exercise file as the class runs it
    PRIMARY KEY (class, k)
);
CREATE TABLE IF NOT EXISTS class_present (  -- the machine a class's instructor presents
    class TEXT PRIMARY KEY,
    machine TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS class_lists (  -- a class's uploaded machine template (none: demo)
    class TEXT PRIMARY KEY,
    channel_list TEXT NOT NULL,
    axis_lists TEXT NOT NULL,      -- JSON {log_achs_nr: text}
    tool_list TEXT NOT NULL
);
"""


class Classes:
    """Every class of the service; the running ones with their machines."""

    def __init__(
        self,
        store: Store,
        accounts: Accounts,
        machines: MachineService,
        exercises: Exercises,
        audit: Audit,
        faults: training.StandingFaults,
        snapshots: training.Snapshots,
    ) -> None:
        self.store = store
        self.faults = faults
        self.snapshots = snapshots
        self.audit = audit
        self.accounts = accounts
        self.machines = machines
        self.exercises = exercises
        store.script(SCHEMA)
        self._lock = threading.RLock()
        self.lock = self._lock  # the lesson plan changes a seat under it too
        self._classes: dict[str, Class] = {}
        self._seat_of: dict[str, Seat] = {}  # login -> seat of a running class
        self._by_machine: dict[str, Seat] = {}
        self._load()

    # --- reading ------------------------------------------------------------------------------
    def _load(self) -> None:
        rows = self.store.query(
            "SELECT id, title, exercise, exercise_text, instructor, created, ended FROM classes"
        )
        templates = {
            t["class"]: MachineLists(
                channel_list=t["channel_list"],
                axis_lists={int(k): v for k, v in json.loads(t["axis_lists"]).items()},
                tool_list=t["tool_list"],
            )
            for t in self.store.query(
                "SELECT class, channel_list, axis_lists, tool_list FROM class_lists"
            )
        }
        presenting = {
            p["class"]: p["machine"]
            for p in self.store.query("SELECT class, machine FROM class_present")
        }
        plans: dict[str, list[str]] = {}
        for p in self.store.query("SELECT class, text FROM class_plan ORDER BY class, k"):
            plans.setdefault(p["class"], []).append(p["text"])
        for r in rows:
            cid = r["id"]
            texts = plans.get(cid) or [r["exercise_text"]]  # a class from before plans
            plan = [parse_exercise(text, f"class {cid}") for text in texts]
            seats = []
            for s in self.store.query(
                "SELECT n, student, user, machine, progress FROM seats WHERE class = ? ORDER BY n",
                (cid,),
            ):
                seat = Seat(cid, s["n"], s["student"], s["user"], s["machine"], plan[0])
                seat.load_progress(s["progress"], plan)
                seats.append(seat)
            c = Class(
                cid,
                r["title"],
                plan,
                texts,
                r["instructor"],
                r["created"],
                r["ended"],
                seats,
                templates.get(cid),
                presenting=presenting.get(cid),
            )
            self._classes[cid] = c
            if r["ended"] is None:
                self._index(c)
                # the machines are built after this (MachineService.load): with the checks
                # and the exercise's faults, unless faults were kept as they stood
                in_force = 0
                for seat in seats:
                    faults = [(f.fault, f.trigger) for f in seat.exercise.faults]
                    self.machines.seats[seat.machine] = (seat.exercise, faults)
                    kept = self.faults.kept(seat.machine)
                    in_force += len(faults if kept is None else kept)
                c.resumed = ClassResumed(
                    at_unix=time.time(),
                    seats=len(seats),
                    faults=in_force,
                    snapshots=sum(self.snapshots.count(seat.machine) for seat in seats),
                )

    def _index(self, c: Class) -> None:
        for seat in c.seats:
            self._seat_of[seat.user] = seat
            self._by_machine[seat.machine] = seat

    def seat_of(self, user: str) -> str | None:
        """The machine a login may see when it is a running class's student, else None."""
        seat = self._seat_of.get(user)
        return seat.machine if seat is not None else None

    def presented_to(self, seat_machine: str) -> str | None:
        """The machine a seat's class presents to it (None: none)."""
        seat = self._by_machine.get(seat_machine)
        return self._classes[seat.class_id].presenting if seat is not None else None

    def present(self, actor: Actor, c: Class, machine: str | None) -> None:
        """Show a machine to every seat, read-only (None: stop); each seat hears it."""
        if machine is not None:
            self.machines.get(machine)  # 404 for none such
        if c.ended_unix is not None:
            raise Conflict(f"class '{c.id}' has ended")
        if machine == c.presenting:
            return
        c.presenting = machine
        if machine is None:
            self.store.run("DELETE FROM class_present WHERE class = ?", (c.id,))
            text = f"{actor.name} stopped presenting"
        else:
            self.store.run("INSERT OR REPLACE INTO class_present VALUES (?, ?)", (c.id, machine))
            text = f"{actor.name} presents machine {machine}: watch it (read-only)"
        for seat in c.seats:
            m = self.proxy(seat)
            if m is not None:
                m.notices.add("present", text)

    def seat_by_machine(self, mid: str) -> tuple[Class, Seat]:
        """The running class and seat of a machine; 404 when it is no seat."""
        with self._lock:
            seat = self._by_machine.get(mid)
            if seat is None:
                raise not_found(f"class seat of machine '{mid}'")
            return self._classes[seat.class_id], seat

    def get(self, cid: str) -> Class:
        c = self._classes.get(cid)
        if c is None:
            raise not_found(f"class '{cid}'")
        return c

    def all(self) -> list[Class]:
        with self._lock:
            return sorted(self._classes.values(), key=lambda c: -c.created_unix)

    def running(self, cid: str) -> Class:
        """A class that has not ended; 404 for none, 409 for one that has ended."""
        c = self.get(cid)
        if c.ended_unix is not None:
            raise Conflict(f"class '{cid}' has ended")
        return c

    def seat(self, cid: str, n: int) -> Seat:
        c = self.get(cid)
        if not 1 <= n <= len(c.seats):
            raise not_found(f"seat {n} of class '{cid}' (seats 1..{len(c.seats)})")
        return c.seats[n - 1]

    def select(self, c: Class, seats: list[int]) -> list[Seat]:
        """The seats numbered (all for an empty list); 404 naming a seat that is none."""
        if not seats:
            return list(c.seats)
        bad = [n for n in seats if not 1 <= n <= len(c.seats)]
        if bad:
            raise not_found(f"seat {bad[0]} of class '{c.id}' (seats 1..{len(c.seats)})")
        return [c.seats[n - 1] for n in sorted(set(seats))]

    def proxy(self, seat: Seat) -> MachineProxy | None:
        try:
            return self.machines.get(seat.machine)
        except ApiError:
            return None

    # --- progress -----------------------------------------------------------------------------
    def checks(self, c: Class, seat: Seat) -> list[CheckState]:
        out = []
        ex = seat.exercise
        earned = {s.id: s.earned for s in exercise_score(ex, seat.first_passed_s).checks}
        for k in ex.checks:
            rule = findings.finding_of(k)
            given = seat.answers.get(k.id, [])
            state = None if rule is None else findings.state(rule, c.seat_machine(seat), given)
            waiting = "not answered yet" if rule is not None else "not evaluated yet"
            out.append(
                CheckState(
                    id=k.id,
                    text=k.text,
                    points=k.points,
                    earned=earned[k.id],
                    passed=seat.passed.get(k.id, False),
                    first_passed_s=seat.first_passed_s.get(k.id),
                    detail=seat.detail.get(k.id, waiting),
                    finding=state,
                )
            )
        return out

    def answer(self, actor: Actor, seat: Seat, c: Class, req: FindingAnswer) -> AnswerGiven:
        """A finding answered by the seat's own student (403 for anyone else: an answer uses
        one of the student's attempts), graded and kept; a right one passes the check at the
        seat time now."""
        if actor.name != seat.user:
            raise Forbidden(
                f"only seat {seat.n}'s student ({seat.student}, login {seat.user}) answers its"
                " findings: an answer uses one of the student's attempts"
            )
        if c.ended_unix is not None:
            raise Conflict(f"class '{c.id}' has ended")
        with self._lock:
            given = findings.answer(seat.exercise, c.seat_machine(seat), seat.answers, req)
            seat.passed[req.check], seat.detail[req.check] = given.passed, given.detail
            if given.passed:
                seat.first_passed_s.setdefault(req.check, seat.seat_time_s)
        self.save(seat)
        return given

    @staticmethod
    def score(seat: Seat) -> tuple[float, float]:
        """(progress 0..1, score) of a seat in its exercise, by nc_sim.training.score's rule
        over the seat times (s) of the checks' first passes."""
        s = exercise_score(seat.exercise, seat.first_passed_s, [n - 1 for n in seat.hints])
        return s.passed / max(1, s.total), s.points

    def update(self, seat: Seat, proxy: MachineProxy) -> bool:
        """Take the seat machine's newest pushed status in (its seat time and check
        results); True when a check passed for the first time. A rebuilt machine's checks
        start again from "nothing measured yet": the figure measured before stays until the
        new build measures one."""
        st = proxy.link.status
        if st is None:
            return False
        t_s = st.pacing.cycle * st.pacing.cycle_s
        if proxy.link.epoch != seat.epoch:  # a new build: the seat's clock goes on from here
            if seat.epoch_start_s is not None:
                seat.time_base_s = seat.seat_time_s
            seat.epoch, seat.epoch_start_s = proxy.link.epoch, t_s
            seat.first_detail = {}
        seat.last_t_s = t_s
        news = False
        for r in st.checks:
            assert isinstance(r, CheckResult)
            cid, passed = r.id, r.passed
            blank = seat.first_detail.setdefault(cid, r.detail) == r.detail and not passed
            seat.passed[cid] = passed
            if not blank or cid not in seat.detail:
                seat.detail[cid] = r.detail
            if passed and cid not in seat.first_passed_s:
                seat.first_passed_s[cid] = seat.seat_time_s
                news = True
        return news

    def save_running(self) -> None:
        """Every running seat's progress as it stands now, stored (the service stops: what
        was measured since the last save is kept)."""
        for c in self.all():
            if c.ended_unix is None:
                for seat in c.seats:
                    proxy = self.proxy(seat)
                    if proxy is not None:
                        self.update(seat, proxy)
                    self.save(seat)

    def save(self, seat: Seat) -> None:
        self.store.run(
            "UPDATE seats SET progress = ? WHERE class = ? AND n = ?",
            (seat.progress_json(), seat.class_id, seat.n),
        )

    def info(self, c: Class) -> ClassInfo:
        return ClassInfo(
            id=c.id,
            title=c.title,
            exercises=[ex.id for ex in c.plan],
            template="demo" if c.lists is None else "lists",
            instructor=c.instructor,
            created_unix=c.created_unix,
            ended_unix=c.ended_unix,
            seats=[self.seat_info(c, s) for s in c.seats],
            resumed=c.resumed if c.ended_unix is None else None,
            presenting=c.presenting,
        )

    def seat_info(self, c: Class, seat: Seat) -> SeatInfo:
        proxy = self.proxy(seat) if c.ended_unix is None else None
        holder = proxy.control.holder if proxy is not None else None
        progress, score = self.score(seat)
        return SeatInfo(
            n=seat.n,
            student=seat.student,
            user=seat.user,
            machine=seat.machine,
            frozen=seat.frozen,
            control=holder.user if holder is not None else None,
            progress=progress,
            score=score,
            hints_taken=len(seat.hints),
            seat_time_s=seat.seat_time_s,
            joined_unix=seat.joined_unix,
            stage=seat.stage,
            done=seat.done,
            total_score=score + sum(d.score for d in seat.done),
        )

    # --- changing -----------------------------------------------------------------------------
    def create(self, actor: Actor, req: ClassCreate, base_url: str) -> ClassCreated:
        """Seats with their logins and machines at the plan's first exercise (its starting
        values written as the instructor's, its faults injected with each seat's own
        numbers, its checks running); a link per seat. Every exercise of the plan must fit
        the machine (422 naming the one that does not)."""
        found = [self.exercises.get(eid) for eid in req.exercises]
        plan, texts = [ex for ex, _ in found], [text for _, text in found]
        for ex in plan:
            self._check_template(ex, req.lists)
        with self._lock:
            if req.id in self._classes:
                raise Conflict(f"class '{req.id}' exists (ended or not)")
            taken = {u.name for u in self.accounts.users()}
            names = [seat_name(req.id, n) for n in range(1, req.seats + 1)]
            clash = [n for n in names if n in taken or self._exists(n)]
            if clash:
                raise Conflict(f"'{clash[0]}' is taken (a user or machine)")
            now = time.time()
            title = req.title or " → ".join(ex.title for ex in plan)[:80]
            c = Class(req.id, title, plan, texts, actor.name, now, None, [], req.lists)
            self._classes[c.id] = c  # reserved while the seats are built
        self._build_seats(actor, c, names, req.students)
        self.store.run(  # its first exercise here too (a store from before plans reads it)
            "INSERT INTO classes VALUES (?, ?, ?, ?, ?, ?, NULL)",
            (c.id, c.title, plan[0].id, texts[0], c.instructor, c.created_unix),
        )
        for k, (ex, text) in enumerate(zip(plan, texts, strict=True)):
            self.store.run("INSERT INTO class_plan VALUES (?, ?, ?, ?)", (c.id, k, ex.id, text))
        if c.lists is not None:
            self.store.run(
                "INSERT INTO class_lists VALUES (?, ?, ?, ?)",
                (
                    c.id,
                    c.lists.channel_list,
                    json.dumps({str(k): v for k, v in c.lists.axis_lists.items()}),
                    c.lists.tool_list,
                ),
            )
        for seat in c.seats:
            self.store.run(
                "INSERT INTO seats VALUES (?, ?, ?, ?, ?, ?)",
                (c.id, seat.n, seat.student, seat.user, seat.machine, seat.progress_json()),
            )
        with self._lock:
            self._index(c)
        hours = req.link_hours
        links = [self.link(s, base_url, hours) for s in c.seats]
        return ClassCreated(info=self.info(c), links=links)

    @staticmethod
    def _check_template(ex: Exercise, lists: MachineLists | None) -> None:
        """422 for lists no machine can be built from (the list's line named, as machine
        creation does) or that lack an axis, spindle or gear stage the exercise needs."""
        template = None
        if lists is not None:
            try:
                template = machine_from_lists(
                    "template", lists.channel_list, lists.axis_lists, lists.tool_list
                )
            except (ParamListError, NcUsageError) as e:
                raise lists_rejected(e) from None
        try:
            check_fits(ex, f"exercise '{ex.id}'", template)
        except (ExerciseError, ParamListError, NcUsageError) as e:
            machine = "the demo lathe" if lists is None else "the uploaded lists"
            raise Invalid(f"{e} (the machine: {machine})") from None

    def _exists(self, mid: str) -> bool:
        try:
            self.machines.get(mid)
        except ApiError:
            return False
        return True

    def _build_seats(self, actor: Actor, c: Class, names: list[str], students: list[str]) -> None:
        """Build every seat, one build in flight per live worker (a worker builds a machine
        in its loop: more at once would only queue there); when one fails, none more
        starts, and every seat built is taken away again before the error goes on."""
        workers = max(1, len(self.machines.pool.alive()))
        built: list[Seat] = []
        with ThreadPoolExecutor(workers, thread_name_prefix="seat-build") as pool:
            futures = [
                pool.submit(
                    self._build_seat,
                    actor,
                    c,
                    n,
                    name,
                    (students[n - 1] if n <= len(students) else f"Seat {n}")[:80],
                )
                for n, name in enumerate(names, start=1)
            ]
            wait(futures, return_when=FIRST_EXCEPTION)
            for f in futures:
                f.cancel()  # those not started yet (a failure: no more builds)
        failure: BaseException | None = None
        for f in futures:
            if f.cancelled():
                continue
            if (e := f.exception()) is not None:
                failure = failure or e
            else:
                built.append(f.result())
        c.seats.extend(sorted(built, key=lambda seat: seat.n))
        if failure is not None:
            self._discard(c)
            raise failure

    def _build_seat(self, actor: Actor, c: Class, n: int, name: str, student: str) -> Seat:
        """A seat's login (no password: only its one-time links log in) and machine; what
        of it was made is taken away again when it fails."""
        self.accounts.add_user(name, Role.OPERATOR, None)
        seat = Seat(c.id, n, student, name, name, c.plan[0])
        c.enter(seat, 0)
        ex = seat.exercise
        try:
            title = f"{c.title} · seat {n}"
            proxy = self.machines.create(
                MachineCreate(
                    id=name,
                    name=title[:80],
                    demo=c.lists is None,
                    **(c.lists.model_dump() if c.lists is not None else {}),
                ),
                values=[(v.scope.value, v.target, v.name, v.value) for v in ex.start],
                faults=[(f.fault, f.trigger) for f in ex.faults],
                exercise=ex,
                mode="pause",  # an empty seat's clock stands: it runs from its student's login
            )
            # the exercise's start, kept: the instructor can put the seat back to it
            self.snapshots.take(actor, proxy, "exercise start", pinned=True)
            changes, entries = start_values(actor, proxy.id, ex)
            if changes:
                self.store.write(proxy.id, changes, entries)
        except BaseException:
            self._remove_seat(seat)
            raise
        return seat

    def _discard(self, c: Class) -> None:
        """Undo a class whose seats could not all be built."""
        for seat in c.seats:
            self._remove_seat(seat)
        with self._lock:
            self._classes.pop(c.id, None)

    def _remove_seat(self, seat: Seat) -> None:
        if self._exists(seat.machine):
            self.machines.delete(seat.machine)
        if any(u.name == seat.user for u in self.accounts.users()):
            self.accounts.remove_user(seat.user)

    def delete(self, c: Class) -> None:
        """Forget an ended class (409 while it runs): its rows go, its id is free again."""
        with self._lock:
            if c.ended_unix is None:
                raise Conflict(f"class '{c.id}' still runs: end it first")
            for table in ("seats", "ended_sessions", "class_lists", "class_plan", "class_present"):
                self.store.run(f"DELETE FROM {table} WHERE class = ?", (c.id,))
            self.store.run("DELETE FROM classes WHERE id = ?", (c.id,))
            del self._classes[c.id]

    def link(self, seat: Seat, base_url: str, hours: float = 1.0) -> SeatLink:
        """A one-time login link of the seat's login (good once, for `hours`); the seat's
        sessions and earlier links end with it (a leaked link is taken back this way)."""
        self.accounts.end_logins_of(seat.user)
        label = f"class {seat.class_id} seat {seat.n}"
        token = self.accounts.new_token(seat.user, label, True, hours * 3600.0)
        url = f"{base_url.rstrip('/')}/auth/once?token={token}"
        return SeatLink(n=seat.n, url=url, expires_unix=time.time() + hours * 3600.0)

    def end(self, c: Class) -> None:
        """The class ends: its machines and logins go, its record stays with each seat's
        final progress and injected faults; the students' sessions still name their seats
        (their pages show the result, `result_of`)."""
        with self._lock:
            if c.ended_unix is not None:
                raise Conflict(f"class '{c.id}' has ended")
            for seat in c.seats:
                proxy = self.proxy(seat)
                if proxy is not None:
                    self.update(seat, proxy)
                    seat.faults = self._last_faults(proxy)
                self._seat_of.pop(seat.user, None)
                self._by_machine.pop(seat.machine, None)
            c.ended_unix = time.time()
            c.presenting = None
        for seat in c.seats:
            self.save(seat)
            for key, expires in self.accounts.sessions_of(seat.user):
                self.store.run(
                    "INSERT OR REPLACE INTO ended_sessions VALUES (?, ?, ?, ?)",
                    (key, c.id, seat.n, expires),
                )
            self._remove_seat(seat)
        self.store.run("UPDATE classes SET ended = ? WHERE id = ?", (c.ended_unix, c.id))
        self.store.run("DELETE FROM class_present WHERE class = ?", (c.id,))

    @staticmethod
    def _last_faults(proxy: MachineProxy) -> list[FaultInfo]:
        """The machine's faults as its worker has them now; its last pushed ones when the
        worker does not answer (the class ends all the same)."""
        try:
            return training.faults_of(proxy)
        except ApiError:
            faults = sorted(proxy.link.faults.values(), key=lambda f: f.id)
            return [training.fault_info(f, proxy.link.cycle_s) for f in faults]

    def result_of(self, sid: str) -> SeatResult | None:
        """The final result of the seat an ended class's session was logged in to (None for
        any other session, or one past its expiry)."""
        rows = self.store.query(
            "SELECT class, n FROM ended_sessions WHERE digest = ? AND expires > ?",
            (digest(sid), time.time()),
        )
        c = self._classes.get(rows[0]["class"]) if rows else None
        if c is None or c.ended_unix is None:
            return None
        seat = self.seat(c.id, rows[0]["n"])
        stages = [*seat.done, self.stage_result(c, seat, "the class's end", c.ended_unix)]
        return SeatResult(
            class_id=c.id,
            title=c.title,
            exercise=" → ".join(d.title for d in stages),
            seat=seat.n,
            student=seat.student,
            ended_unix=c.ended_unix,
            score=sum(d.score for d in stages),
            max_points=sum(d.max_points for d in stages),
            checks_passed=sum(1 for d in stages for k in d.checks if k.first_passed_s is not None),
            checks_total=sum(len(d.checks) for d in stages),
            hints_taken=sum(d.hints_taken for d in stages),
            seat_time_s=sum(d.seat_time_s for d in stages),
            stages=stages,
        )

    def stage_result(self, c: Class, seat: Seat, by: str, at_unix: float) -> StageResult:
        """The seat's exercise as it stands now, as a result of the plan."""
        ex = seat.exercise
        s = exercise_score(ex, seat.first_passed_s, [n - 1 for n in seat.hints])
        passes = [seat.first_passed_s.get(k.id) for k in ex.checks]
        finished = max(p for p in passes if p is not None) if None not in passes else None
        return StageResult(
            exercise=ex.id,
            title=ex.title,
            score=s.points,
            max_points=s.max_points,
            checks=self.checks(c, seat),
            hints_taken=len(seat.hints),
            hint_cost=s.hint_cost,
            seat_time_s=seat.seat_time_s,
            finished_s=finished,
            values=seat.values,
            moved_on_by=by,
            moved_on_unix=at_unix,
        )

    def forget_result(self, sid: str) -> None:
        """The student logged out of their ended seat: its session names it no more."""
        self.store.run("DELETE FROM ended_sessions WHERE digest = ?", (digest(sid),))

    def freeze(self, seats: list[Seat], frozen: bool, by: str) -> None:
        """Pause (or run again) the seats' machines, each with a banner on its HMI (resumed
        by the instructor, a seat nobody has joined yet runs: the instructor's start)."""
        for seat in seats:
            m = self.machines.get(seat.machine)
            m.link.call(Pace(m.id, "pause" if frozen else "run"))
            m.control.frozen_by = by if frozen else None  # its student cannot take control
            seat.frozen = frozen
            self.save(seat)
            word = "froze" if frozen else "resumed"
            m.notices.add("frozen" if frozen else "resumed", f"{by} {word} the machine")

    def refreeze(self) -> None:
        """After the machines are built at start-up: the seats frozen before pause again, and
        so do those nobody has joined yet (their clock stands)."""
        for c in self.all():
            if c.ended_unix is None:
                waiting = [
                    s
                    for s in c.seats
                    if (s.frozen or s.joined_unix is None) and self.proxy(s) is not None
                ]
                for seat in waiting:
                    m = self.machines.get(seat.machine)
                    m.link.call(Pace(m.id, "pause"))
                    if seat.frozen:
                        m.control.frozen_by = c.instructor

    def joined(self, user: str) -> None:
        """A login of a seat's student: the first one starts the seat's clock (its machine
        runs, unless the instructor froze it)."""
        with self._lock:
            seat = self._seat_of.get(user)
            if seat is None or seat.joined_unix is not None:
                return
            seat.joined_unix = time.time()
            self.save(seat)
        m = self.proxy(seat)
        if m is not None and not seat.frozen:
            m.link.call(Pace(m.id, "run"))

    def check_unlocked(self, mid: str, assistant: str, actor: Actor) -> None:
        """403 when the machine is a running class's seat, the asker its student, and the
        seat's exercise locks the assistant (an instructor may use it there)."""
        seat = self._by_machine.get(mid)
        if seat is not None and actor.name == seat.user and assistant in seat.exercise.locked:
            raise Forbidden(
                f"the exercise '{seat.exercise.title}' locks the {assistant} assistant: "
                "work it out by hand"
            )

    def broadcast(self, seats: list[Seat], text: str, by: str) -> None:
        """A message as a banner on every one of the seats' HMIs."""
        for seat in seats:
            self.machines.get(seat.machine).notices.add("message", f"{by}: {text}")

    def inject(self, seats: list[Seat], req: FaultInject, actor: Actor) -> list[SeatFaults]:
        """A fault into each of the seats' machines (each audited on its machine); every
        seat's faults as they stand after."""
        what = training.describe(training.to_fault(req.fault))
        out = []
        for seat in seats:
            m = self.machines.get(seat.machine)
            training.inject(m, req)
            self.audit.record(self.entry(actor, f"inject fault: {what}", m.id, **req.model_dump()))
            out.append(SeatFaults(n=seat.n, faults=self.faults.keep(m)))
        return out

    def hand(self, actor: Actor, seat: Seat, c: Class, req: HandRequest) -> RaisedHand | None:
        """The seat's student raises or lowers their hand; an instructor lowers it (seen to).
        403 for anyone else, 409 once the class has ended."""
        teacher = Action.TEACH in ALLOWED[actor.role]
        if actor.name != seat.user and (req.raised or not teacher):
            raise Forbidden(
                f"only seat {seat.n}'s student raises its hand; an instructor lowers it"
            )
        if c.ended_unix is not None:
            raise Conflict(f"class '{c.id}' has ended")
        with self._lock:
            seat.hand = RaisedHand(since_unix=time.time(), text=req.text) if req.raised else None
            self.save(seat)
        return seat.hand

    def take_hint(self, actor: Actor, seat: Seat, c: Class, n: int) -> str:
        """A hint's text; taken once, it costs its points. Only the seat's own student takes
        one (403 for anyone else: an instructor watching would charge the student)."""
        if actor.name != seat.user:
            raise Forbidden(
                f"only seat {seat.n}'s student ({seat.student}, login "
                f"{seat.user}) takes its hints: a hint costs the student's points"
            )
        hints = seat.exercise.hints
        if not 1 <= n <= len(hints):
            raise not_found(f"hint {n} (hints 1..{len(hints)})")
        with self._lock:
            seat.hints.add(n)
        self.save(seat)
        return hints[n - 1].text

    @staticmethod
    def entry(actor: Actor, action: str, machine: str = "", **detail: object) -> Entry:
        """An audit row of kind 'training'."""
        return Entry(actor.name, actor.session, "training", action, machine, dict(detail))
