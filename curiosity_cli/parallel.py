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
"""

from __future__ import annotations

import contextlib
import os
import uuid
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

from curiosity_cli.errors import CuriosityError, ParameterError

#: Where the tasks of a command can be computed: joblib's loky processes, or a Dask cluster.
BACKENDS = ("loky", "dask")

#: Seconds a command waits for a first worker to join a Dask scheduler that has none.
WORKER_WAIT_SECONDS = 60


class BackendError(CuriosityError):
    """The Dask backend cannot run: its optional dependency is missing, or its cluster is unusable."""


def threads_per_job(jobs: int) -> int:
    """Threads each of ``jobs`` parallel jobs may use so that together they use the cores once."""
    return max(1, (os.cpu_count() or 1) // max(1, jobs))


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
        Worker processes (of ``loky``, or of the local Dask cluster); default the number
        of cores. Ignored with a ``scheduler``: the cluster's worker threads decide.

    Raises
    ------
    ParameterError
        An unknown backend, or a scheduler without ``backend="dask"``.
    BackendError
        ``backend="dask"`` without Dask distributed installed (reported before any work).
    """

    def __init__(self, backend: str = "loky", scheduler: str | None = None, jobs: int | None = None):
        if backend not in BACKENDS:
            raise ParameterError(f"backend: got {backend!r}, expected one of {', '.join(BACKENDS)}")
        if scheduler is not None and backend != "dask":
            raise ParameterError(f"scheduler: got {scheduler!r} with backend {backend!r}; a scheduler needs backend 'dask'")
        if backend == "dask":
            import_distributed()
        self.backend = backend
        self.scheduler = scheduler
        self.jobs = (os.cpu_count() or 1) if jobs is None else jobs
        self._stack = contextlib.ExitStack()
        self._dask = None  # (client, threads per task) once reached
        self._files = {}  # shipped files' futures, by (path, loader)

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
        """
        if self.backend == "loky":
            from joblib import Parallel, delayed

            threads = threads_per_job(self.jobs) if threads is None else threads
            results = Parallel(n_jobs=self.jobs, backend="loky", return_as="generator_unordered")(
                delayed(_outcome)(i, function, task, threads, *args(task)) for i, task in enumerate(tasks)
            )
            with contextlib.closing(results):
                yield ((tasks[i], outcome) for i, outcome in results)
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


def _outcome(index: int, function: Callable, task, threads: int, *args) -> tuple:
    """``(index, function(task, *args, threads=threads))``, or ``(index, "ErrorType: message")``."""
    try:
        return index, function(task, *args, threads=threads)
    except Exception as exc:  # noqa: BLE001 - reported with the task's name, the others go on
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
            cluster = stack.enter_context(distributed.LocalCluster(
                n_workers=jobs, threads_per_worker=1, processes=True, host="127.0.0.1",
                dashboard_address=None, silence_logs=logging.ERROR,
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
