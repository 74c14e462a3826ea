"""Where a command's tasks run: joblib's loky processes on this machine, or a Dask cluster.

Exploration runs, batch references and label tasks all go through :class:`Workers`:

- **One map.** :meth:`Workers.compute` computes ``function(task, *args(task),
  threads=…)`` for every task and yields ``(task, outcome)`` as each finishes, whatever
  the backend; an exception comes back as its text (``"RuntimeError: …"``) so that one
  failing task does not stop the others, and leaving the iteration early stops the tasks
  still in flight. The same function computes a task on either backend, so results are
  identical.
- **loky.** ``jobs`` worker processes of this machine; a worker reads the files it needs
  itself and keeps what it loaded for the tasks after.
- **Dask** (``backend="dask"``): at ``scheduler``'s address, or on a ``LocalCluster`` of
  ``jobs`` one-thread worker processes started on first use and shut down when the
  :class:`Workers` context exits, so the stages of one command share it. Files go to the
  cluster once (:meth:`Workers.ship_file`), as the argument of a task that loads them (no
  shared filesystem needed); tasks that depend on it get the loaded value once per
  worker, from a peer, and if every copy is lost with its workers the scheduler loads it
  again (scattered data could not be recomputed). A task lost with its worker is
  rescheduled on another by the scheduler (up to
  ``distributed.scheduler.allowed-failures`` times); a task whose workers keep dying comes
  back as ``KilledWorker`` text, like a task that raised. Workers must have this process's
  versions of the package, numpy and numba.

Either way:

- ``jobs`` is at most this machine's cores: the tasks are CPU-bound, so more processes
  only add memory (and each one semaphores), and a mistyped ``--jobs 100000`` would try
  to start them all.
- Ctrl-C reaches every process of the terminal's process group, but only this process
  acts on it: loky workers ignore SIGINT (:func:`_settle_worker`) and are killed by
  joblib as the interruption unwinds; a local cluster's workers ignore SIGINT
  (:func:`dask_setup`) and are shut down with the cluster. (A Ctrl-C in the second a
  worker takes to start can still reach it.) A Ctrl-C or SIGTERM while the local
  cluster starts takes effect once it has started, as a cluster interrupted half-made
  cannot be closed quietly.
- A loky worker whose command was killed outright (``kill -9``) exits within
  :data:`ORPHAN_POLL_SECONDS`, instead of lingering until loky's idle timeout (300 s).
- The warnings the libraries raise while tasks run (e.g. loky replacing a worker) are
  shown as one ``note:`` line each, not as their raw text.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time
import uuid
import warnings
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

from curiosity_cli.errors import CuriosityError, ParameterError, unwinding_interrupt

#: Where the tasks of a command can be computed: joblib's loky processes, or a Dask cluster.
BACKENDS = ("loky", "dask")

#: Seconds a command waits for a first worker to join a Dask scheduler that has none.
WORKER_WAIT_SECONDS = 60

#: How often (s) a loky worker checks that the command that started it is still alive.
ORPHAN_POLL_SECONDS = 1.0

#: What the known library warnings mean, by the start of their text.
_WARNING_MEANINGS = {
    "A worker stopped while some jobs were given to the executor": (
        "a worker process was replaced (loky restarts a worker whose memory grew by more than 300 MB "
        "since its first task); the command goes on"
    ),
}


class BackendError(CuriosityError):
    """The Dask backend cannot run: its optional dependency is missing, or its cluster is unusable."""


def cores() -> int:
    """This machine's cores: the most worker processes a command starts here."""
    return os.cpu_count() or 1


def threads_per_job(jobs: int) -> int:
    """Threads each of ``jobs`` parallel jobs may use so that together they use the cores once."""
    return max(1, cores() // max(1, jobs))


def _check_jobs(jobs: int) -> None:
    """Refuse a number of worker processes this machine cannot usefully run (module docstring).

    Raises
    ------
    ParameterError
    """
    if not 1 <= jobs <= cores():
        raise ParameterError(f"jobs: got {jobs}, expected 1 to {cores()} (the cores of this machine)")


def import_distributed():
    """The ``distributed`` module.

    Raises
    ------
    BackendError
        Dask distributed is not installed, with the command that installs it.
    """
    try:
        import distributed
    except ImportError as exc:
        raise BackendError(
            f"the dask backend needs Dask distributed, which is not installed ({exc}); "
            "install it from the checkout with: pip install -e '.[distributed]'"
        ) from None
    return distributed


class Workers:
    """The processes a command's tasks run on (module docstring); a context manager.

    Parameters
    ----------
    backend : {"loky", "dask"}
    scheduler : str, optional
        With ``backend="dask"``: a running scheduler's address, e.g.
        ``tcp://10.0.0.5:8786``; without one, a local cluster is started on first use.
    jobs : int, optional
        Worker processes (of ``loky``, or of the local Dask cluster), 1 to the number of
        cores; default the number of cores. Ignored with a ``scheduler``: the cluster's
        worker threads decide.

    Raises
    ------
    ParameterError
        An unknown backend, a scheduler without ``backend="dask"``, or ``jobs`` outside
        1 to the number of cores.
    BackendError
        ``backend="dask"`` without Dask distributed installed (reported before any work).
    """

    def __init__(self, backend: str = "loky", scheduler: str | None = None, jobs: int | None = None):
        if backend not in BACKENDS:
            raise ParameterError(f"backend: got {backend!r}, expected one of {', '.join(BACKENDS)}")
        if scheduler is not None and backend != "dask":
            raise ParameterError(f"scheduler: got {scheduler!r} with backend {backend!r}; a scheduler needs backend 'dask'")
        if jobs is not None and scheduler is None:
            _check_jobs(jobs)
        if backend == "dask":
            import_distributed()
        self.backend = backend
        self.scheduler = scheduler
        self.jobs = cores() if jobs is None else jobs
        self._stack = contextlib.ExitStack()
        self._dask = None  # (client, threads per task) once reached
        self._files = {}  # shipped files' futures, by (path, loader)

    @classmethod
    def shared(
        cls, workers: Workers | None, backend: str = "loky", scheduler: str | None = None, jobs: int | None = None,
    ) -> contextlib.AbstractContextManager[Workers]:
        """What a stage computes on: ``workers`` another stage shares (left open when the stage
        ends), else new ones from ``backend``, ``scheduler`` and ``jobs``, checked now, before
        any work, and stopped when the stage ends (a local cluster with them)."""
        return contextlib.nullcontext(workers) if workers is not None else cls(backend, scheduler, jobs)

    def __enter__(self) -> Workers:
        return self

    def __exit__(self, *exc) -> None:
        self._files.clear()
        self._stack.close()

    @property
    def ships(self) -> bool:
        """Whether tasks get their inputs shipped (Dask) rather than reading this machine's files (loky)."""
        return self.backend == "dask"

    def ship_file(self, path: Path, load: Callable):
        """Dask only: a future of ``load(path)``, computed on a worker from the file's bytes, sent once per command.

        ``load`` is a module-level function of a path (e.g. :func:`~curiosity_cli.words.store.load_store`).
        """
        key = (str(path), load)
        if key not in self._files:
            client, _ = self._client()
            self._files[key] = client.submit(
                _loaded_from_bytes, load, Path(path).name, Path(path).read_bytes(),
                key=f"{load.__name__}-{Path(path).stem}-{_token()}",
            )
        return self._files[key]

    def ship(self, build: Callable, *args, key: str):
        """Dask only: a future of ``build(*args)``, computed once on a worker; ``args`` may hold futures.

        For values built from arrays of this process (they travel with the task, so the
        scheduler can build the value again if it is lost).
        """
        client, _ = self._client()
        return client.submit(build, *args, key=f"{key}-{_token()}")

    def whole_machine_threads(self, tasks: int) -> int:
        """Threads for each of ``tasks`` long tasks run at once (a map's batch reference), a machine's cores between them.

        With loky or a local cluster, this machine's cores shared by the tasks that run
        at once; on a cluster someone started, the largest worker's threads (the tasks
        are few, and spread over the workers).
        """
        if self.backend == "dask" and self.scheduler is not None:
            client, _ = self._client()
            return max(client.nthreads().values())
        return threads_per_job(min(self.jobs, tasks))

    @contextlib.contextmanager
    def compute(
        self, function: Callable, tasks: Sequence, *, args: Callable = lambda task: (),
        key: Callable = str, threads: int | None = None,
    ) -> Iterator[Iterator[tuple]]:
        """An iterator of ``(task, outcome)`` for every task, in the order they finish.

        Parameters
        ----------
        function : callable
            Module-level, called as ``function(task, *args(task), threads=threads)`` in a worker.
        tasks : sequence
        args : callable, optional
            A task's further arguments (its shipped inputs: futures on Dask).
        key : callable, optional
            A task's name on the Dask dashboard (unique among ``tasks``).
        threads : int, optional
            Threads each task may use; default each worker's share of its machine's cores
            (loky, a local cluster) or one per worker thread (a cluster someone started).

        Yields
        ------
        iterator of (task, outcome)
            ``outcome`` is what ``function`` returned, or a ``str``: the exception it
            raised (``"RuntimeError: …"``), or why the cluster could not compute it.
            Leaving the context early stops the tasks still in flight.

        Raises
        ------
        BackendError
            While iterating, with loky: a worker process died (e.g. killed by the
            operating system for lack of memory).
        """
        with _warnings_as_notes():
            if self.backend == "loky":
                from joblib import Parallel, delayed, parallel_config

                threads = threads_per_job(self.jobs) if threads is None else threads
                # (joblib computes n_jobs=1 in this process: no worker, no initializer)
                with parallel_config(backend="loky", initializer=_settle_worker, initargs=(os.getpid(),)):
                    results = Parallel(n_jobs=self.jobs, return_as="generator_unordered")(
                        delayed(_outcome)(i, function, task, threads, *args(task)) for i, task in enumerate(tasks)
                    )
                with contextlib.closing(results):
                    yield _loky_outcomes(results, tasks)
            elif not tasks:  # nothing to compute: start no cluster
                yield iter(())
            else:
                client, default = self._client()
                threads = default if threads is None else threads
                with contextlib.closing(_dask_outcomes(client, function, tasks, args, key, threads, _token())) as outcomes:
                    yield outcomes

    def _client(self):
        if self._dask is None:
            self._dask = self._stack.enter_context(dask_client(self.scheduler, self.jobs))
        return self._dask


def _token() -> str:
    """A suffix that keeps task keys apart from those of other submissions, and other commands, on one cluster."""
    return uuid.uuid4().hex[:8]


@contextlib.contextmanager
def _warnings_as_notes():
    """Show the warnings raised meanwhile (in any thread of this process) as one ``note:`` line each."""
    with warnings.catch_warnings():
        # leaving the iteration early is how a caller stops the tasks in flight: nothing to advise
        warnings.filterwarnings("ignore", message=r"\d+ tasks which were still being processed", category=UserWarning)
        warnings.showwarning = _show_note
        yield


def _show_note(message, category, filename, lineno, file=None, line=None) -> None:
    """A :func:`warnings.showwarning` that writes what a warning means in one line on stderr."""
    text = " ".join(str(message).split())
    meaning = next((m for start, m in _WARNING_MEANINGS.items() if text.startswith(start)), None)
    print(f"note: {meaning or f'{category.__name__} from {filename}: {text}'}", file=sys.stderr, flush=True)


def _loky_outcomes(results, tasks: Sequence):
    """Yield ``(task, outcome)`` from joblib's ``(index, outcome)`` results; a dead worker becomes a BackendError."""
    from joblib.externals.loky.process_executor import TerminatedWorkerError

    try:
        for i, outcome in results:
            yield tasks[i], outcome
    except TerminatedWorkerError as exc:
        codes = str(exc).partition("exit codes of the workers are ")[2].partition("}")[0].lstrip("{") or "unknown"
        raise BackendError(
            f"a worker process died (exit codes {codes}; the operating system kills a process when memory runs "
            "out: try fewer jobs); finished work is kept, run the same command again to resume"
        ) from None


def _settle_worker(parent: int) -> None:
    """Run by each loky worker as it starts: leave Ctrl-C to ``parent``, the command, and exit once it is gone.

    loky itself would keep the workers of a killed command until their idle timeout (300 s).
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threading.Thread(target=_watch_parent, args=(parent,), name="orphan-watch", daemon=True).start()


def _watch_parent(parent: int) -> None:
    while os.getppid() == parent:
        time.sleep(ORPHAN_POLL_SECONDS)
    os._exit(1)  # the parent is gone: nobody will read this worker's results


def _outcome(index: int, function: Callable, task, threads: int, *args) -> tuple:
    """``(index, function(task, *args, threads=threads))``, or ``(index, "ErrorType: message")``."""
    try:
        return index, function(task, *args, threads=threads)
    except Exception as exc:  # noqa: BLE001 - reported with the task's name, the others go on
        if unwinding_interrupt(exc):  # in this process (one job): the command stops, not the task
            raise
        return index, f"{type(exc).__name__}: {exc}"


def _dask_outcomes(client, function: Callable, tasks: Sequence, args: Callable, key: Callable, threads: int, token: str):
    """Yield ``(task, outcome)`` as the cluster finishes each task, all submitted at once (module docstring)."""
    from distributed import KilledWorker, as_completed

    futures = {
        client.submit(_outcome, i, function, task, threads, *args(task), key=f"{key(task)}-{token}"): i
        for i, task in enumerate(tasks)
    }
    try:
        for future in as_completed(futures, loop=client.loop):
            task = tasks[futures[future]]
            try:
                _, outcome = future.result()
            except KilledWorker:
                outcome = "KilledWorker: every worker that ran it died (out of memory?); see the workers' logs"
            except Exception as exc:  # noqa: BLE001 - e.g. its shipped input was lost with the workers; the others go on
                outcome = f"{type(exc).__name__}: {exc}"
            future.release()
            yield task, outcome
    finally:  # stopped early: the cluster need not finish the rest
        client.cancel([future for future in futures if not future.done()])


@contextlib.contextmanager
def dask_client(scheduler: str | None, jobs: int):
    """A client of the cluster at ``scheduler`` (or of a local cluster started here), and each task's threads.

    On a local cluster of ``jobs`` one-thread processes, tasks share the machine's cores
    as with loky; on a cluster someone started, a task gets one thread per worker
    thread (give workers one thread per core, ``dask worker``'s default).

    Raises
    ------
    BackendError
        A scheduler that cannot be reached or gets no worker, or workers with other
        versions of the package, numpy or numba than this process.
    """
    import logging

    distributed = import_distributed()
    with contextlib.ExitStack() as stack:
        if scheduler is None:
            with _signals_deferred():
                cluster = stack.enter_context(distributed.LocalCluster(
                    n_workers=jobs, threads_per_worker=1, processes=True, host="127.0.0.1",
                    # Every fault of a local cluster reaches the command as a task outcome
                    # (KilledWorker) or a BackendError; its log lines only add noise, such
                    # as a worker's heartbeat racing the scheduler's shutdown on Ctrl-C.
                    dashboard_address=None, silence_logs=logging.CRITICAL, preload=[__name__],
                    # no dashboard, and the scheduler's HTTP routes on a free port, not on 8787
                    scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                ))
            client = stack.enter_context(distributed.Client(cluster, set_as_default=False))
            threads = threads_per_job(jobs)
        else:
            try:
                client = stack.enter_context(distributed.Client(scheduler, set_as_default=False))
            except (OSError, ValueError) as exc:
                raise BackendError(
                    f"cannot reach the Dask scheduler at {scheduler} ({exc}); start one with `dask scheduler` "
                    "and pass the address it prints"
                ) from None
            threads = 1
        try:
            client.wait_for_workers(1, timeout=WORKER_WAIT_SECONDS)
        except TimeoutError:
            raise BackendError(
                f"the Dask scheduler at {scheduler} has no worker after {WORKER_WAIT_SECONDS} s; "
                f"start some with `dask worker {scheduler}`"
            ) from None
        _check_worker_versions(client)
        yield client, threads


@contextlib.contextmanager
def _signals_deferred():
    """Hold SIGINT and SIGTERM received in the block, and raise them again once it has ended."""
    received = []
    previous = {s: signal.signal(s, lambda signum, frame: received.append(signum)) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    for signum in dict.fromkeys(received):
        signal.raise_signal(signum)


def dask_setup(worker) -> None:
    """Run by each worker of a local cluster as it starts (this module is its preload): ignore Ctrl-C.

    The command that started the cluster handles Ctrl-C and shuts the cluster down; a
    worker interrupted by it on its own would log its tracebacks. (Ignoring SIGINT in the
    command while it starts the cluster, for the workers to inherit, would lose a Ctrl-C
    pressed meanwhile.)
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _versions() -> tuple[str, str, str]:
    """What a task's numbers depend on besides its inputs: this package's, numpy's and numba's versions."""
    from importlib.metadata import version

    from curiosity_cli import __version__

    return __version__, version("numpy"), version("numba")


def _check_worker_versions(client) -> None:
    """Refuse workers whose results could differ from this process's: other package, numpy or numba versions."""
    try:
        found = client.run(_versions)
    except Exception as exc:  # noqa: BLE001 - e.g. the package is not installed on a worker
        raise BackendError(
            f"the Dask workers cannot run curiosity ({type(exc).__name__}: {exc}); "
            "install the same version of curiosity on every worker machine"
        ) from None
    here = _versions()
    for address, theirs in sorted(found.items()):
        if tuple(theirs) != here:
            names = ("curiosity", "numpy", "numba")
            diff = ", ".join(f"{n} {t} (here {h})" for n, t, h in zip(names, theirs, here) if t != h)
            raise BackendError(
                f"the Dask worker at {address} has {diff}; its runs could differ, so install the same versions "
                "on every worker machine"
            )


def _loaded_from_bytes(load: Callable, name: str, data: bytes):
    """``load`` of a file from its bytes: how a Dask worker gets a file of this machine."""
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / name
        path.write_bytes(data)
        return load(path)
