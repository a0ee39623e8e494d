"""The worker zygote: the process every local worker is forked from.

A worker started as a new interpreter spends about half a core-second importing numba and the
kernel and loading its compiled functions before it can run a cycle. The zygote does that once,
at the first worker's request; every worker is then a fork of a process that has the kernel
loaded (several at start, a successor after a crash): it runs within milliseconds, and the
workers share the loaded kernel's memory.

`inbetrieb serve` forks the zygote from itself before it opens its store or starts a thread (a
fork copies only the thread that forks: no lock another thread held is copied held). A process
that has threads already (a test, a bench) starts it as a new interpreter instead. Either way
the zygote has one thread, ignores SIGINT and SIGTERM as the workers do (the gateway stops its
workers in order), and ends when the gateway's end of its socket closes, however the gateway
ends. A worker is the zygote's child; the gateway watches it through a pidfd.
"""

from __future__ import annotations

import atexit
import functools
import os
import pickle
import signal
import socket
import subprocess
import sys
import threading
import traceback
from collections.abc import Callable
from typing import Any, NoReturn

MAX_REQUEST = 1 << 20  # a request: the gateway's environment and the worker's arguments


class ZygoteGone(RuntimeError):
    """The zygote ended (killed): the next `get` starts another."""


class Zygote:
    """The gateway's end of a zygote."""

    def __init__(self, ctrl: socket.socket, pid: int, proc: subprocess.Popen[bytes] | None):
        self._ctrl = ctrl
        self.pid = pid
        self._proc = proc  # when started as a new interpreter
        self._lock = threading.Lock()
        self.ended = False

    @classmethod
    def start(cls) -> Zygote:
        """Fork it from this process while it has one thread, else start a new interpreter."""
        ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        proc = None
        if threading.active_count() == 1:
            pid = os.fork()
            if pid == 0:  # the zygote
                ours.close()
                _as_child(functools.partial(serve, theirs))
        else:
            fd = theirs.fileno()
            cmd = [sys.executable, "-m", "backend.workers.zygote", str(fd)]
            proc = subprocess.Popen(cmd, pass_fds=[fd])
            pid = proc.pid
        theirs.close()
        return cls(ours, pid, proc)

    def fork_worker(
        self,
        main: Callable[..., None],
        sock: socket.socket,
        args: tuple[Any, ...],
        timeout_s: float,
    ) -> int:
        """Fork a worker that runs `main(sock, *args)` (a module's function: it travels by
        name) with this process' environment as it is now; its pid."""
        request = pickle.dumps((main, dict(os.environ), args))
        with self._lock:
            try:
                self._ctrl.settimeout(timeout_s)  # the first request loads the kernel
                socket.send_fds(self._ctrl, [request], [sock.fileno()])
                reply = self._ctrl.recv(8)
            except OSError as e:
                reply = b""
                cause: Exception | None = e
            else:
                cause = None
            if len(reply) != 8:  # ended, or too slow: left (it ends when its socket closes)
                self.ended = True
                self._ctrl.close()
                self._ended()
                raise ZygoteGone(f"the worker zygote (pid {self.pid}) ended") from cause
        return int.from_bytes(reply, "little")

    def close(self) -> None:
        """End it (its workers run on until their own sockets close)."""
        self.ended = True
        self._ctrl.close()
        if self._proc is not None:
            try:
                self._proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        else:
            self._ended()

    def running(self) -> bool:
        """Whether it still runs."""
        self.ended = self.ended or self._ended()
        return not self.ended

    def _ended(self) -> bool:
        """Whether the process ended (its exit collected then: no zombie is left)."""
        if self._proc is not None:
            return self._proc.poll() is not None
        try:
            return os.waitpid(self.pid, os.WNOHANG)[0] != 0
        except ChildProcessError:
            return True


_current: Zygote | None = None
_current_lock = threading.Lock()


def get() -> Zygote:
    """This process' zygote: started at the first call (and again after it ended)."""
    global _current
    with _current_lock:
        if _current is None or not _current.running():
            if _current is None:
                atexit.register(_close)
            _current = Zygote.start()
        return _current


def fork_worker(
    main: Callable[..., None], sock: socket.socket, args: tuple[Any, ...], timeout_s: float
) -> int:
    """Fork a worker from this process' zygote (`Zygote.fork_worker`). A zygote found ended
    (killed after the last look) is replaced at once, once; one too slow is not tried again."""
    try:
        return get().fork_worker(main, sock, args, timeout_s)
    except ZygoteGone as e:
        if isinstance(e.__cause__, TimeoutError):
            raise
        return get().fork_worker(main, sock, args, timeout_s)


def _close() -> None:
    with _current_lock:
        if _current is not None:
            _current.close()


def serve(ctrl: socket.socket) -> int:
    """The zygote: fork a worker for each request until the gateway's end closes."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)
    signal.signal(signal.SIGCHLD, signal.SIG_IGN)  # the kernel reaps the workers
    while True:
        try:
            request, fds, _, _ = socket.recv_fds(ctrl, MAX_REQUEST, 1)
        except OSError:
            return 0
        if not request or not fds:
            return 0  # the gateway went away
        # imported here: the gateway process never loads the kernel
        from backend.workers.warmup import warm_up

        warm_up()  # at the first request, at normal priority: every worker forked has it
        main, env, args = pickle.loads(request)
        pid = os.fork()
        if pid == 0:
            ctrl.close()
            _as_child(functools.partial(_run_worker, main, fds[0], env, args))
        os.close(fds[0])
        ctrl.send(pid.to_bytes(8, "little"))


def _run_worker(
    main: Callable[..., None], fd: int, env: dict[str, str], args: tuple[Any, ...]
) -> int:
    """A forked worker: the gateway's environment, then its `main`."""
    os.environ.clear()
    os.environ.update(env)
    signal.signal(signal.SIGCHLD, signal.SIG_DFL)
    main(socket.socket(fileno=fd), *args)
    return 0


def _as_child(run: Callable[[], int]) -> NoReturn:
    """The rest of a forked child's life: `run`, whose result is the exit code (an exception
    prints its traceback and exits 1); never back into the code that forked it."""
    code = 1
    try:
        code = run()
    except BaseException:
        traceback.print_exc()
    finally:
        for stream in (sys.stdout, sys.stderr):
            stream.flush()
        os._exit(code)


if __name__ == "__main__":  # started as a new interpreter by a process with threads
    sys.exit(serve(socket.socket(fileno=int(sys.argv[1]))))
