"""`inbetrieb user add|list|remove|passwd|link` and `inbetrieb token create|list|revoke`: people
on the command line, straight in the store (the service need not run; a running one closes
the websockets of what ended here within seconds)."""

from __future__ import annotations

import argparse
import getpass
import sys
import time
from pathlib import Path

from api.auth import MIN_PASSWORD, Role
from backend.services.accounts import AccountError, Accounts, BadPassword
from backend.services.store import Store
from backend.settings import Settings


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    db_help = "SQLite file (default var/inbetrieb.sqlite)"
    p_user = sub.add_parser("user", help="add, list, remove users or set a password")
    users = p_user.add_subparsers(dest="action", required=True)
    p_add = users.add_parser("add", help="add a user (asks for the password)")
    p_add.add_argument("name")
    p_add.add_argument("--role", choices=[r.value for r in Role], default=Role.OPERATOR.value)
    p_list = users.add_parser("list", help="every user with their role")
    p_rm = users.add_parser("remove", help="remove a user, their sessions and tokens")
    p_rm.add_argument("name")
    p_pw = users.add_parser("passwd", help="set a user's password (their sessions end)")
    p_pw.add_argument("name")
    p_link = users.add_parser(
        "link", help="print a one-time login link of a user (good once, within an hour)"
    )
    p_link.add_argument("name")
    p_link.add_argument(
        "--url",
        default="http://127.0.0.1:8000",
        help="the address browsers reach the service by (default http://127.0.0.1:8000)",
    )
    p_tok = sub.add_parser("token", help="API tokens for scripts")
    tokens = p_tok.add_subparsers(dest="action", required=True)
    p_new = tokens.add_parser("create", help="print a new API token of a user")
    p_new.add_argument("--user", required=True)
    p_new.add_argument("--label", default="", help="what it is for (shown in the audit)")
    p_tlist = tokens.add_parser("list", help="API tokens (public ids, never the tokens)")
    p_tlist.add_argument("--user", help="only this user's")
    p_revoke = tokens.add_parser("revoke", help="revoke an API token by its public id")
    p_revoke.add_argument("id", help="as `token list` shows it (token-...)")
    for p in (p_add, p_list, p_rm, p_pw, p_link, p_new, p_tlist, p_revoke):
        p.add_argument("--db", type=Path, help=db_help)
    for p in (p_add, p_pw):
        p.add_argument("--password-stdin", action="store_true", help="read the password from stdin")


def _password(args: argparse.Namespace) -> str:
    if args.password_stdin:
        pw = sys.stdin.readline().rstrip("\n")
    else:
        pw = getpass.getpass("password: ")
        if getpass.getpass("again: ") != pw:
            raise BadPassword("the passwords differ")
    if len(pw) < MIN_PASSWORD:
        raise BadPassword(f"a password has at least {MIN_PASSWORD} characters")
    return pw


def _when(t: float | None) -> str:
    return time.strftime("%Y-%m-%d %H:%M", time.localtime(t)) if t else "never"


def _token(accounts: Accounts, args: argparse.Namespace) -> None:
    if args.action == "create":
        print(accounts.new_token(args.user, args.label))
    elif args.action == "list":
        for t in accounts.tokens(args.user):
            used = _when(t.last_used)
            print(f"{t.id}\t{t.user}\t{_when(t.created)}\tlast used {used}\t{t.label}")
    elif args.action == "revoke":
        accounts.revoke_token(args.id)


def run(args: argparse.Namespace) -> int:
    """Carry out a `user` or `token` command; 0, or 2 with the reason on stderr."""
    store = Store(args.db or Settings().db_path)
    accounts = Accounts(store)
    try:
        if args.cmd == "token":
            _token(accounts, args)
        elif args.action == "add":
            accounts.add_user(args.name, Role(args.role), _password(args))
        elif args.action == "list":
            for me in accounts.users():
                print(f"{me.name}\t{me.role.value}")
        elif args.action == "remove":
            accounts.remove_user(args.name)
        elif args.action == "passwd":
            accounts.set_password(args.name, _password(args))
        elif args.action == "link":
            # the first login on a server, where the service prints no link (not on loopback)
            token = accounts.new_token(args.name, "printed by `inbetrieb user link`", once=True)
            print(f"{args.url.rstrip('/')}/auth/once?token={token}")
    except AccountError as e:
        print(f"inbetrieb {args.cmd}: {e}", file=sys.stderr)
        return 2
    finally:
        store.close()
    return 0
