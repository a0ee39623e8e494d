"""Who may do what. Roles and actions are part of the contract so the UI can show them."""

from __future__ import annotations

from enum import StrEnum


class Role(StrEnum):
    """Roles of a user of the HMI."""

    OBSERVER = "observer"  # watches status and telemetry
    OPERATOR = "operator"  # commands the machine, edits parameters
    INSTRUCTOR = "instructor"  # also creates, deletes and paces machines for a class


class Action(StrEnum):
    """What a request does, as the single authorization point sees it."""

    OBSERVE = "observe"
    COMMAND = "command"
    CONFIGURE = "configure"  # parameter writes and imports
    SIMULATE = "simulate"  # run, pause, step, fast
    ADMINISTER = "administer"  # create, restart, delete machines


ALLOWED: dict[Role, frozenset[Action]] = {
    Role.OBSERVER: frozenset({Action.OBSERVE}),
    Role.OPERATOR: frozenset({Action.OBSERVE, Action.COMMAND, Action.CONFIGURE}),
    Role.INSTRUCTOR: frozenset(Action),
}
