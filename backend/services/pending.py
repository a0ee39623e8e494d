"""Parameter values a machine accepted that wait for a reset or a restart to take effect (the
gateway shows them beside the value in force, and the reset or restart hands them over)."""

from __future__ import annotations

from dataclasses import dataclass

from nc_sim.params import Value

Key = tuple[str, str, str]  # (scope, target, list name)


@dataclass
class Pending:
    """An accepted value that waits for reset or restart."""

    value: Value
    effect: str


class PendingValues(dict[Key, Pending]):
    """One machine's waiting values by (scope, target, name); guarded by its proxy's lock.
    A rebuild or restart takes every stored value, so they are cleared then."""

    def value(self, key: Key) -> Value | None:
        """The value waiting for `key`, None when none waits."""
        p = self.get(key)
        return p.value if p is not None else None
