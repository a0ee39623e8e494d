"""The `inbetrieb` command: `sim` runs a scenario headless, `assist` a commissioning
assistant, `serve` starts the service,
`openapi` writes the API schema the browser's types are generated from."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pydantic import ValidationError

from backend.services import migrations, store_lock
from backend.services.store import STEPS
from backend.settings import Settings
from nc_sim.errors import NcUsageError
from nc_sim.params import ParamListError


def main(argv: list[str] | None = None) -> int:
    # here, not at the top: a process that multiprocessing spawns (the assistants' pool)
    # imports this module again as its main module, and needs none of their code
    from backend import cli_accounts, cli_assist, cli_backup

    parser = argparse.ArgumentParser(prog="inbetrieb", description=__doc__)
    sub = parser.add_subparsers(dest="cmd", required=True)
    p_sim = sub.add_parser("sim", help="run a TOML scenario as fast as possible")
    p_sim.add_argument("scenario", type=Path)
    p_sim.add_argument("--out", type=Path, default=Path("out"))
    p_srv = sub.add_parser("serve", help="start the web service")
    p_srv.add_argument("--host", help="the address to bind (default 127.0.0.1)")
    p_srv.add_argument("--port", type=int, help="its port (default 8000)")
    p_srv.add_argument("--db", type=Path, help="SQLite file (default var/inbetrieb.sqlite)")
    p_srv.add_argument("--no-demo", action="store_true", help="no demo machine in a new store")
    p_srv.add_argument("--workers", type=int, help="worker processes (default: one per core)")
    p_srv.add_argument(
        "--cluster",
        help="Ray cluster: the head's GCS address HOST:PORT when the gateway runs on a cluster "
        "node, or ray://HOST:PORT (Ray Client, the head's port 10001 by default) from anywhere "
        "else, shipping the gateway's code to the actors; workers become Ray actors spread "
        "over the nodes",
    )
    p_srv.add_argument(
        "--allowed-host",
        action="append",
        default=[],
        metavar="NAME",
        help="a Host name clients reach the service by (repeat for more); loopback names "
        "and the --host address are always allowed",
    )
    p_srv.add_argument(
        "--recordings-quota-mb",
        type=float,
        metavar="MB",
        help="disk space all recordings together may take (default 2048)",
    )
    p_srv.add_argument("--tls-cert", type=Path, help="TLS certificate (PEM) to serve HTTPS")
    p_srv.add_argument("--tls-key", type=Path, help="its private key (PEM)")
    p_srv.add_argument(
        "--behind-proxy",
        metavar="ADDRESS",
        help="served through a reverse proxy at ADDRESS that terminates TLS: its "
        "X-Forwarded-For/-Proto headers are trusted, nobody else's",
    )
    p_api = sub.add_parser("openapi", help="write the OpenAPI schema (with websocket models)")
    p_api.add_argument("--out", type=Path, default=Path("var/openapi.json"))
    cli_accounts.add_parsers(sub)
    cli_assist.add_parsers(sub)
    cli_backup.add_parsers(sub)
    args = parser.parse_args(argv)
    if args.cmd in ("user", "token"):
        return cli_accounts.run(args)
    if args.cmd in ("backup", "restore"):
        return cli_backup.run(args)
    if args.cmd == "assist":
        return cli_assist.run(args)
    if args.cmd == "openapi":
        import json

        from backend.main import app

        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(app.openapi(), indent=1) + "\n")
        return 0
    if args.cmd == "sim":
        from backend.headless import run_file

        try:
            result = run_file(args.scenario, args.out)
        except (ParamListError, NcUsageError, OSError, ValueError) as e:
            print(f"inbetrieb sim: {e}", file=sys.stderr)
            return 2
        errors = [e for e in result.events if e.error]
        rows = len(next(iter(result.columns.values())))
        print(f"{rows} cycles, {len(result.events)} events ({len(errors)} errors) -> {args.out}")
        return 0
    # an option given wins over its INBETRIEB_* variable (a container's or a unit's settings)
    given = {
        "host": args.host,
        "port": args.port,
        "db_path": args.db,
        "demo": False if args.no_demo else None,
        "workers": args.workers,
        "cluster": args.cluster,
        "recordings_quota_mb": args.recordings_quota_mb,
        "allowed_hosts": args.allowed_host or None,
        "tls_cert": args.tls_cert,
        "tls_key": args.tls_key,
        "behind_proxy": args.behind_proxy,
    }
    try:
        settings = Settings.model_validate({k: v for k, v in given.items() if v is not None})
    except ValidationError as e:
        for err in e.errors():
            where = ".".join(str(x) for x in err["loc"])
            print(f"inbetrieb serve: {where}: {err['msg']}", file=sys.stderr)
        return 2
    if settings.cluster is None:
        # the local workers' zygote, forked now: this process has one thread and has opened
        # nothing yet (its store, its port) that the zygote would hold too
        from backend.workers import zygote

        zygote.get()
    try:  # before anything starts: a store of a newer release, or served already, is left
        migrations.check_file(settings.db_path, STEPS)
        held = store_lock.hold(settings.db_path)  # for as long as this process serves
    except (migrations.StoreTooNew, store_lock.StoreInUse) as e:
        print(f"inbetrieb serve: {e}", file=sys.stderr)
        return 2
    from backend.server import serve  # the app, once the settings are known to be good

    try:
        return serve(settings)
    finally:
        held.close()


if __name__ == "__main__":
    sys.exit(main())
