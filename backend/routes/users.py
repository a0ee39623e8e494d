"""Users, for admins: list, add, change role or password, remove. Nobody removes themselves,
and the last admin stays one (409); a new password or a removal ends the user's sessions,
whose websockets close within seconds."""

from __future__ import annotations

from fastapi import APIRouter, Response

from api.auth import Action, UserChange, UserCreate, UserInfo
from backend.deps import ActorDep, ServicesDep, permit
from backend.errors import CREATED, NO_CONTENT, Conflict, Invalid, NotFound, responses
from backend.services.accounts import Accounts, UserEntry
from backend.services.audit_log import Entry

router = APIRouter(prefix="/api/users", tags=["users"])


def _user_info(u: UserEntry) -> UserInfo:
    return UserInfo(name=u.name, role=u.role, created_unix=u.created)


def _info(accounts: Accounts, name: str) -> UserInfo:
    user = next((u for u in accounts.users() if u.name == name), None)
    if user is None:
        raise NotFound(f"no user {name!r}")
    return _user_info(user)


@router.get("", dependencies=[permit(Action.USERS)])
def list_users(services: ServicesDep) -> list[UserInfo]:
    """Every user with their role, oldest first."""
    return [_user_info(u) for u in services.accounts.users()]


@router.post(
    "",
    status_code=CREATED,
    dependencies=[permit(Action.USERS)],
    responses=responses(Conflict, why={Conflict: "the name is taken"}),
)
def add_user(req: UserCreate, services: ServicesDep, actor: ActorDep) -> UserInfo:
    """A new user with a role and password."""
    services.accounts.add_user(req.name, req.role, req.password)
    services.audit.record(
        Entry(
            actor.name,
            actor.session,
            "user",
            f"added user {req.name}",
            detail={"user": req.name, "role": req.role.value},
        )
    )
    return _info(services.accounts, req.name)


@router.patch(
    "/{name}",
    dependencies=[permit(Action.USERS)],
    responses=responses(
        NotFound, Conflict, why={Conflict: "the last admin", Invalid: "nothing to change"}
    ),
)
def change_user(name: str, req: UserChange, services: ServicesDep, actor: ActorDep) -> UserInfo:
    """A new role and/or password; a new password ends the user's sessions."""
    if req.role is None and req.password is None:
        raise Invalid("give a role or a password to change")
    detail: dict[str, str] = {"user": name}
    if req.role is not None:
        services.accounts.set_role(name, req.role)
        detail["role"] = req.role.value
    if req.password is not None:
        services.accounts.set_password(name, req.password)
        detail["password"] = "changed"  # never the password
    if req.password is not None:
        services.sessions.poke()
    services.audit.record(
        Entry(actor.name, actor.session, "user", f"changed user {name}", detail=detail)
    )
    return _info(services.accounts, name)


@router.delete(
    "/{name}",
    status_code=NO_CONTENT,
    response_class=Response,
    dependencies=[permit(Action.USERS)],
    responses=responses(NotFound, Conflict, why={Conflict: "yourself, or the last admin"}),
)
def remove_user(name: str, services: ServicesDep, actor: ActorDep) -> Response:
    """Remove a user with their sessions and tokens."""
    if name == actor.name:
        raise Conflict("you cannot remove yourself: ask another admin")
    services.accounts.remove_user(name)
    services.sessions.poke()
    services.audit.record(
        Entry(actor.name, actor.session, "user", f"removed user {name}", detail={"user": name})
    )
    return Response(status_code=NO_CONTENT)
