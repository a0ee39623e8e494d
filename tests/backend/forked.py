"""Test services forked from a process that has imported the service already.

`inbetrieb serve` in a new interpreter spends about two thirds of a core-second importing
FastAPI and building the app's 160 routes before it serves, and a run starts about 140
services. Each test process therefore keeps one fork server (multiprocessing's "forkserver":
a single-threaded process started once, that has imported `backend.cli` and `backend.main`
and loaded the kernel) and forks every service from it: the same `inbetrieb serve` entry point
with the same arguments, environment and output, in a process of its own that then runs its
own workers as always (forked from its own zygote, which finds the kernel loaded). Tests about
the command line itself (Ctrl-C reaching the process group, the exit of a refused start) still
run `python -m backend.cli` as a subprocess."""

from __future__ import annotations

import io
import multiprocessing
import os
import signal
import subprocess
import sys
from multiprocessing import reduction
from pathlib import Path
from typing import Any

_FORKS = multiprocessing.get_context("forkserver")
# "__main__": a script's main module (a bench's) is imported once, by the fork server, not
# again in every service (pytest's is not imported at all)
_PRELOAD = ["__main__", "backend.cli", "backend.main", "tests.backend.forked"]
_FORKS.set_forkserver_preload([*_PRELOAD, "tests.backend.kernel_loaded"])


class _Fd:
    """A file descriptor of this process, handed to the forked service (as a subprocess
    inherits its output): pickled, it travels to the fork server with the process."""

    def __init__(self, fd: int) -> None:
        self.fd = fd

    def __reduce__(self) -> tuple[Any, tuple[Any]]:
        return _opened, (reduction.DupFd(self.fd),)


def _opened(duplicate: Any) -> int:
    fd: int = duplicate.detach()
    return fd


def _serve(argv: list[str], env: dict[str, str], cwd: Path, stdout: int, stderr: int) -> None:
    """The forked service: the environment, working directory and output a subprocess would
    have, then `inbetrieb serve` as from the command line."""
    os.environ.clear()
    os.environ.update(env)
    os.chdir(cwd)
    os.dup2(stdout, 1)
    os.dup2(stderr, 2)
    for fd in {stdout, stderr} - {1, 2}:
        os.close(fd)
    for stream in (sys.stdout, sys.stderr):  # unbuffered, as PYTHONUNBUFFERED makes them
        if isinstance(stream, io.TextIOWrapper):
            stream.reconfigure(write_through=True)
    from backend.cli import main

    sys.exit(main(argv))


class ForkedService:
    """A forked `inbetrieb serve`, with the part of `subprocess.Popen` the tests use."""

    def __init__(
        self, argv: list[str], env: dict[str, str], cwd: Path, stdout: int = 1, stderr: int = 2
    ) -> None:
        """`inbetrieb <argv>` in `cwd` with the environment `env` (the whole of it), its
        output to the file descriptors `stdout` and `stderr` of this process."""
        args = (argv, env, cwd, _Fd(stdout), _Fd(stderr))
        self.process = _FORKS.Process(target=_serve, args=args, name="inbetrieb serve")
        self.process.start()
        assert self.process.pid is not None
        self.pid: int = self.process.pid

    @property
    def returncode(self) -> int | None:
        """The exit code once it ended (minus the signal that ended it), else None."""
        return self.process.exitcode

    def poll(self) -> int | None:
        return self.returncode

    def send_signal(self, sig: int) -> None:
        if self.returncode is None:
            os.kill(self.pid, sig)

    def kill(self) -> None:
        self.send_signal(signal.SIGKILL)

    def wait(self, timeout: float | None = None) -> int:
        self.process.join(timeout)
        code = self.returncode
        if code is None:
            raise subprocess.TimeoutExpired("inbetrieb serve", timeout or 0.0)
        return code
