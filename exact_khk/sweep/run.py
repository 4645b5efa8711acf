"""Running a sweep: the results file, resuming, and the engines.

Engines (each runs :func:`exact_khk.sweep.tasks.run_task` on plain JSON payloads):

* :class:`LocalEngine` — the standard library's
  :class:`concurrent.futures.ProcessPoolExecutor` on this machine's cores
  (``forkserver`` start method where available, else ``spawn``; workers
  ignore Ctrl-C, the parent stops them).  At most one task per worker is in
  flight, so a task's clock starts when it is handed over.  A task still
  running ``grace`` seconds after its time limit (stuck in one C call that the
  in-worker limit cannot interrupt) is recorded as TIMEOUT and the pool's
  processes are killed and replaced; the other tasks that were running are
  resubmitted.  A worker process that dies (killed, out of memory) breaks the
  pool: the tasks that were running are rerun one at a time, and a task whose
  worker dies while it runs alone is recorded as ERROR.
* :class:`DaskEngine` — a Dask ``distributed`` cluster (``--dask ADDRESS``, or
  ``local`` for a :class:`distributed.LocalCluster`).  Up to twice as many
  tasks as the cluster has threads are in flight.  The in-worker limit applies
  (a Dask worker runs tasks in threads: the watchdog of
  :func:`~exact_khk.sweep.tasks.time_limit`); a task whose result has not come
  ``2 × timeout + grace`` seconds after submission is recorded as TIMEOUT and
  cancelled (a thread stuck in C keeps its worker busy until it returns).
* :class:`InlineEngine` — in this process, one task after the other
  (``--workers 0``; debugging, and the engine-free baseline of docs/sweeps.md).

The results file ``DIR/results.jsonl`` has one JSON object per line, written to
the operating system (one ``write``) as each task finishes — a sweep killed
with ``kill -9`` loses no finished task — and fsync'ed in batches, at most
:data:`SYNC_SECONDS` after it was written and when the sweep ends: a machine
crash or power cut loses at most that window's lines (their tasks run again).
A rerun reads the file, drops a last line cut short by a crash, and skips every
task of the spec whose key has a record; the latest record of a key counts.  ``--only VERDICTS`` reruns the
tasks whose latest record has one of those verdicts (``failed`` = ERROR and
TIMEOUT).  One sweep at a time may write to DIR (a lock file, POSIX).
"""

from __future__ import annotations

import codecs
import json
import os
import queue
import sys
import time
from collections import Counter, deque
from dataclasses import dataclass, field
from pathlib import Path

from exact_khk.errors import InputError, OutputError
from exact_khk.parsing import _short
from exact_khk.studies.output import check_writable, prepare_folder, write_atomic
from exact_khk.sweep.tasks import (ENGINE_VERDICTS, FAILED, TASKS, VERDICTS, checked_timeout, make_record, now_iso,
                                   run_task, worker_info)

RESULTS = "results.jsonl"
META = "sweep.json"
LOCK = ".sweep.lock"
#: verdict groups understood by ``--only``
GROUPS = {"failed": FAILED}
#: a results line is fsync'ed at most this many seconds after it was written (a background
#: thread syncs the file while lines wait).  One fsync per line cost 0.2–5 ms on the 2-core test
#: machine, up to ten times a no-op task (scripts/bench_sweep.py).
SYNC_SECONDS = 1.0
#: modules imported once by the fork server, before it forks the local workers
PRELOAD = ["exact_khk.sweep.tasks", "exact_khk.certification.lie_poisson", "exact_khk.certification.engine",
           "exact_khk.studies.scaling"]


def default_workers() -> int:
    """The cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


#: the most local worker processes per core (``--workers``, also for ``--dask local``): every
#: worker is a process running CPU-bound tasks, so more only costs memory and switching
MAX_WORKERS_PER_CORE = 4


def checked_workers(workers):
    """``workers`` (None: the default) if it is a sensible number of local worker processes,
    else :class:`InputError` (a typo such as 10000 would start a process per task)."""
    if workers is None:
        return None
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 0:
        raise InputError(f"--workers: expected a non-negative integer, got {workers!r}")
    cores = default_workers()
    if workers > MAX_WORKERS_PER_CORE * cores:
        raise InputError(f"--workers: {workers} is more than {MAX_WORKERS_PER_CORE} per core of this machine "
                         f"({cores} cores: at most {MAX_WORKERS_PER_CORE * cores}); every worker is a process")
    return workers


def default_grace(timeout) -> float:
    """Seconds past the time limit before a task is stopped from outside."""
    return max(5.0, 0.25 * timeout) if timeout else 0.0


# --- the results file --------------------------------------------------------------


def checked_out(out_dir):
    """``out_dir`` unless it is empty (which would be the current folder)."""
    if os.fspath(out_dir) == "":
        raise InputError("--out: expected a folder, got an empty name")
    return out_dir


class ResultStore:
    """``DIR/results.jsonl``: read (tolerating a cut last line), appended line by line
    (each line one ``write``; fsync'ed by a background thread within ``sync_seconds``
    and on :meth:`close`)."""

    def __init__(self, out_dir, sync_seconds=None):
        self.dir = Path(checked_out(out_dir))
        self.path = self.dir / RESULTS
        self.bad_lines = 0
        self.sync_seconds = SYNC_SECONDS if sync_seconds is None else sync_seconds
        self._fh = None
        self._syncer = None

    def read(self) -> list:
        """Every record in file order (lines that are not JSON objects are counted in
        ``bad_lines`` and skipped); :class:`InputError` for a line no sweep writes (not
        UTF-8, JSON nested too deeply): the file is not a sweep's results."""
        if not self.path.exists():
            return []
        out = []
        try:
            with open(self.path, "rb") as fh:
                for number, line in enumerate(fh, 1):
                    if not line.strip():
                        continue
                    try:
                        rec = json.loads(_line_text(line))
                    except UnicodeDecodeError:
                        raise self._not_results(number, "is not UTF-8 text") from None
                    except RecursionError:
                        raise self._not_results(number, "nests JSON too deeply") from None
                    except ValueError:
                        self.bad_lines += 1
                        continue
                    if isinstance(rec, dict) and isinstance(rec.get("key"), str) and "verdict" in rec:
                        out.append(rec)
                    else:
                        self.bad_lines += 1
        except OSError as exc:
            raise OutputError(f"--out: cannot read {str(self.path)!r}: {exc.strerror or exc}") from None
        return out

    def _not_results(self, number, why) -> InputError:
        return InputError(f"--out: {str(self.path)!r} is not the results file of a sweep: line {number} {why}")

    def latest(self) -> dict:
        """key -> its latest record."""
        return {rec["key"]: rec for rec in self.read()}

    def open(self):
        """Open for appending; a last line without its newline (a crash mid-write) is cut off."""
        try:
            if self.path.exists():
                with open(self.path, "rb+") as fh:
                    data = fh.read()
                    if data and not data.endswith(b"\n"):
                        fh.truncate(data.rfind(b"\n") + 1)
            # unbuffered: one write per line, whole lines only reach the file
            self._fh = open(self.path, "ab", buffering=0)
        except OSError as exc:
            raise OutputError(f"--out: cannot write {str(self.path)!r}: {exc.strerror or exc}") from None
        self._syncer = _Syncer(self._fh.fileno(), self.sync_seconds)
        return self

    def append(self, record: dict) -> None:
        """One line, handed to the operating system in one write before returning (it
        survives the sweep's process being killed); fsync'ed within ``sync_seconds``."""
        line = json.dumps(record, ensure_ascii=False, separators=(",", ":")) + "\n"
        try:
            self._syncer.check()
            data = line.encode("utf-8")
            while data:  # a regular file takes the whole line at once; a short write is finished
                data = data[self._fh.write(data):]
            self._syncer.dirty()
        except OSError as exc:
            raise OutputError(f"--out: cannot write {str(self.path)!r}: {exc.strerror or exc}") from None

    def close(self):
        """Sync what is not yet synced, then close."""
        if self._fh is None:
            return
        syncer, self._syncer = self._syncer, None
        try:
            syncer.stop()
        except OSError as exc:
            raise OutputError(f"--out: cannot write {str(self.path)!r}: {exc.strerror or exc}") from None
        finally:
            self._fh.close()
            self._fh = None


class _Syncer:
    """fsync of one file descriptor in a background thread, at most ``window`` seconds
    after :meth:`dirty`; :meth:`stop` syncs a last time (in the caller) and ends the thread.
    A failed background sync is raised by the next :meth:`check` or :meth:`stop`."""

    def __init__(self, fd, window):
        import threading

        self.fd, self.window, self.error = fd, window, None
        self._dirty = False
        self._wake = threading.Condition()
        self._stopped = False
        self._thread = threading.Thread(target=self._run, name="results-fsync", daemon=True)
        self._thread.start()

    def dirty(self):
        if not self._dirty:
            with self._wake:
                self._dirty = True
                self._wake.notify()

    def check(self):
        if self.error is not None:
            raise self.error

    def _run(self):
        with self._wake:
            while True:
                while not self._dirty and not self._stopped:
                    self._wake.wait()
                deadline = time.monotonic() + self.window  # let the lines of one window gather
                while not self._stopped and deadline > time.monotonic():
                    self._wake.wait(deadline - time.monotonic())
                if self._stopped:
                    return  # stop() syncs
                self._dirty = False  # a line written from now on waits for the next sync
                self._wake.release()
                try:
                    os.fsync(self.fd)  # stop() joins this thread before the file is closed
                except OSError as exc:
                    self.error = exc
                finally:
                    self._wake.acquire()
                if self.error is not None:
                    return

    def stop(self):
        with self._wake:
            self._stopped = True
            self._wake.notify()
        self._thread.join()
        self.check()
        os.fsync(self.fd)


def _line_text(line: bytes) -> str:
    """The text of a line of the results file; a last line cut short by a crash (no newline)
    may end inside a character, which is left out."""
    if line.endswith(b"\n"):
        return line.decode("utf-8")
    return codecs.getincrementaldecoder("utf-8")().decode(line)  # not final: a cut character waits


class _Lock:
    """An exclusive lock on DIR (POSIX ``flock``; elsewhere no lock)."""

    def __init__(self, out_dir):
        self.path = Path(out_dir) / LOCK
        self.fh = None

    def __enter__(self):
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX
            return self
        try:
            self.fh = open(self.path, "a")
            fcntl.flock(self.fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            self.fh.close()
            raise OutputError(f"--out: another sweep is writing to {str(self.path.parent)!r}") from None
        except OSError as exc:
            raise OutputError(f"--out: cannot lock {str(self.path)!r}: {exc.strerror or exc}") from None
        return self

    def __exit__(self, *exc):
        if self.fh is not None:
            self.fh.close()  # releases the lock


# --- what to run ------------------------------------------------------------------------


def parse_only(text, task: str | None = None) -> frozenset:
    """``--only``: comma-separated verdicts of :data:`~exact_khk.sweep.tasks.VERDICTS`
    (any case) or groups (``failed``); with ``task``, only verdicts that kind of task
    can give (its own and the engine's)."""
    if text is None:
        return None
    out = set()
    for part in str(text).split(","):
        p = part.strip()
        if not p:
            continue
        if p.lower() not in GROUPS and p.upper() not in VERDICTS:
            raise InputError(f"--only: unknown verdict {_short(p, 40)}; verdicts: {', '.join(VERDICTS)}; "
                             f"groups: {', '.join(GROUPS)}")
        out.update(GROUPS.get(p.lower(), (p.upper(),)))
    if not out:
        raise InputError("--only: give verdicts such as 'failed', 'inconclusive' or 'timeout,error'")
    if task in TASKS:
        possible = (*TASKS[task].verdicts, *ENGINE_VERDICTS)
        never = sorted(v for v in out if v not in possible)
        if never:
            raise InputError(f"--only: {task} tasks never give {', '.join(never)} (they give "
                             f"{', '.join(v for v in VERDICTS if v in possible)})")
    return frozenset(out)


def select(tasks, latest: dict, only=None) -> list:
    """The tasks to run: those without a record, or (``only``) those whose latest
    record has one of the verdicts in ``only``."""
    if only is None:
        return [t for t in tasks if t.key not in latest]
    return [t for t in tasks if t.key in latest and latest[t.key]["verdict"] in only]


# --- engines ------------------------------------------------------------------------


def _engine_record(payload, verdict, error, seconds, engine):
    info = worker_info(engine)
    info["pid"] = None  # the task's worker is gone or unknown; this is the parent
    return make_record(payload, verdict, error=error, seconds=seconds, worker=info)


class InlineEngine:
    """Every task in this process, one after the other."""

    name = "inline"

    def __init__(self):
        self.slots = 1

    def describe(self) -> str:
        return "this process (no workers)"

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def run(self, payloads, on_record, timeout=None, grace=None):
        for p in payloads:
            on_record(run_task(dict(p, engine=self.name)))


def _worker_init(parent_pid=None):  # pragma: no cover - runs in the worker processes
    import signal
    import threading

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C: the parent stops the pool
    if hasattr(sys, "set_int_max_str_digits"):
        sys.set_int_max_str_digits(0)
    if parent_pid is not None:  # a sweep killed without warning leaves no worker behind
        threading.Thread(target=_watch_parent, args=(parent_pid,), daemon=True).start()


def _watch_parent(pid):  # pragma: no cover - runs in the worker processes
    while True:
        time.sleep(1.0)
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            os._exit(1)
        except OSError:
            pass


class LocalEngine:
    """A process pool on this machine (see the module docstring)."""

    name = "local"

    def __init__(self, workers=None, tick: float = 0.25):
        self.workers = self.slots = workers or default_workers()
        self.tick = tick
        self._pool = None

    def describe(self) -> str:
        return f"{self.workers} local worker process{'es' if self.workers != 1 else ''}"

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._stop(kill=exc[0] is not None)
        return False

    def _start(self):
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        method = "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"
        ctx = multiprocessing.get_context(method)
        if method == "forkserver":  # every worker starts with the libraries imported
            ctx.set_forkserver_preload(PRELOAD)
        self._pool = ProcessPoolExecutor(self.workers, mp_context=ctx, initializer=_worker_init,
                                         initargs=(os.getpid(),))
        self._fresh = True  # no task submitted to this pool yet
        try:  # a pool whose processes cannot start must not pass for tasks that kill their worker
            self._pool.submit(os.getpid).result(timeout=120)
        except Exception as exc:  # noqa: BLE001 - BrokenProcessPool, TimeoutError, ...
            self._stop(kill=True)
            raise RuntimeError(f"the local worker processes do not start ({type(exc).__name__}: {exc}); "
                               "try --workers 0 (in this process) or --dask local") from None

    def _stop(self, kill=False):
        pool, self._pool = self._pool, None
        if pool is None:
            return
        if kill:
            procs = list((getattr(pool, "_processes", None) or {}).values())
            for proc in procs:
                try:
                    proc.kill()
                except (OSError, AttributeError):
                    pass
            pool.shutdown(wait=False, cancel_futures=True)
            for proc in procs:
                proc.join(5)
        else:
            pool.shutdown(wait=True)

    def run(self, payloads, on_record, timeout=None, grace=None):
        from concurrent.futures import FIRST_COMPLETED, wait
        from concurrent.futures.process import BrokenProcessPool

        grace = default_grace(timeout) if grace is None else grace
        pending = deque(dict(p, engine=self.name) for p in payloads)
        suspects = deque()     # tasks running when a worker died: rerun alone
        inflight = {}          # future -> (payload, start, alone)
        if self._pool is None:
            self._start()

        def submit(queue, alone):
            """Start the next task of ``queue``; False (the task back in its queue) when the
            pool broke since the last wait (a worker died in between: BrokenProcessPool, or
            on Python 3.11 an OSError from the pool's closing wake-up pipe)."""
            p = queue.popleft()
            try:
                inflight[self._pool.submit(run_task, p)] = (p, time.monotonic(), alone)
                self._fresh = False
                return True
            except (BrokenProcessPool, OSError) as exc:
                queue.appendleft(p)
                if self._fresh:  # a pool just started that takes no task: restarting would loop
                    self._stop(kill=True)
                    raise RuntimeError(f"the local worker pool refuses tasks ({type(exc).__name__}: {exc}); "
                                       "try --workers 0 (in this process) or --dask local") from None
                return False

        while pending or suspects or inflight:
            started = True
            if suspects and not inflight:
                started = submit(suspects, True)
            while started and pending and not suspects and len(inflight) < self.workers:
                started = submit(pending, False)
            wait_for = 0 if not started else self.tick
            if timeout and inflight:
                first = min(t0 for _, t0, _ in inflight.values())
                wait_for = max(0.01, min(wait_for, first + timeout + grace - time.monotonic()))
            done, _ = wait(list(inflight), timeout=wait_for, return_when=FIRST_COMPLETED)
            broken, dead = [], False
            for f in done:
                p, t0, alone = inflight.pop(f)
                try:
                    rec = f.result()
                except BrokenProcessPool:
                    dead = True
                    if alone:
                        on_record(_engine_record(p, "ERROR", "the worker process died while running this task "
                                                 "(killed, or out of memory)", time.monotonic() - t0, self.name))
                    else:
                        broken.append(p)
                    continue
                except Exception as exc:  # noqa: BLE001 - e.g. a result that cannot be pickled
                    from exact_khk.sweep.tasks import error_text

                    rec = _engine_record(p, "ERROR", error_text(exc), time.monotonic() - t0, self.name)
                on_record(rec)
            if dead or not started or any(f.done() and isinstance(f.exception(), BrokenProcessPool)
                                          for f in inflight):
                # the pool is unusable: rerun what was running, one at a time
                for f, (p, _, _) in list(inflight.items()):
                    broken.append(p)
                inflight.clear()
                suspects.extend(broken)
                self._stop(kill=True)
                self._start()
                continue
            if timeout:
                now = time.monotonic()
                overdue = [f for f, (_, t0, _) in inflight.items() if now - t0 > timeout + grace]
                if overdue:
                    for f in overdue:
                        p, t0, _ = inflight.pop(f)
                        on_record(_engine_record(p, "TIMEOUT", f"time limit of {timeout:g} s exceeded (the worker "
                                                 f"did not stop; killed after {now - t0:.1f} s)", now - t0,
                                                 self.name))
                    for f, (p, _, alone) in inflight.items():  # innocent bystanders: run again
                        (suspects if alone else pending).appendleft(p)
                    inflight.clear()
                    self._stop(kill=True)
                    self._start()


class DaskEngine:
    """A Dask distributed cluster: an address, ``'local'`` (a LocalCluster with
    ``workers`` single-threaded worker processes), or an existing ``client``."""

    name = "dask"

    def __init__(self, address=None, workers=None, client=None, tick: float = 0.25):
        self.address, self.workers, self.tick = address, workers, tick
        self.client, self._own_client, self._cluster = client, client is None, None
        self.slots = 1

    def describe(self) -> str:
        where = ("a LocalCluster" if self.address == "local" else
                 f"the scheduler at {self.address}" if self.address else "a Dask client")
        return f"Dask: {where} ({self.slots} worker thread{'s' if self.slots != 1 else ''})"

    def __enter__(self):
        try:
            import distributed
        except ImportError:
            raise InputError("--dask needs the optional package 'distributed' "
                             "(pip install 'exact_khk[sweep]')") from None
        if self.client is None:
            try:
                if self.address == "local":
                    import logging
                    import signal

                    # the worker processes start with Ctrl-C ignored (an ignored signal stays ignored in a
                    # child): Ctrl-C stops the sweep in this process, not with a traceback from each worker
                    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
                    try:
                        self._cluster = distributed.LocalCluster(
                            n_workers=self.workers or default_workers(), threads_per_worker=1, processes=True,
                            dashboard_address=None, silence_logs=logging.ERROR)
                    finally:
                        signal.signal(signal.SIGINT, old)
                    self.client = distributed.Client(self._cluster)
                else:
                    self.client = distributed.Client(self.address, timeout="15s")
            except (OSError, TimeoutError, ValueError) as exc:  # ValueError: not an address ('bogus')
                self._close()
                raise InputError(f"--dask: cannot connect to the scheduler at {self.address}: "
                                 f"{' '.join(str(exc).split()) or type(exc).__name__}") from None
        self.slots = max(1, sum(self.client.nthreads().values()))
        return self

    def __exit__(self, *exc):
        self._close()
        return False

    def _close(self):
        if self._own_client and self.client is not None:
            self.client.close()
            self.client = None
        if self._cluster is not None:
            self._cluster.close()
            self._cluster = None

    def run(self, payloads, on_record, timeout=None, grace=None):
        from exact_khk.sweep.tasks import error_text

        grace = default_grace(timeout) if grace is None else grace
        done_q = queue.Queue()
        pending = deque(dict(p, engine=self.name) for p in payloads)
        inflight = {}  # future key -> (future, payload, submitted)
        window = 2 * max(1, sum(self.client.nthreads().values()) or 1)
        while pending or inflight:
            while pending and len(inflight) < window:
                p = pending.popleft()
                fut = self.client.submit(run_task, p, pure=False)
                inflight[fut.key] = (fut, p, time.monotonic())
                fut.add_done_callback(done_q.put)
            try:
                fut = done_q.get(timeout=self.tick)
            except queue.Empty:
                fut = None
            while fut is not None:
                item = inflight.pop(fut.key, None)
                if item is not None:
                    _, p, t0 = item
                    try:
                        rec = fut.result()
                    except Exception as exc:  # noqa: BLE001 - KilledWorker, CancelledError, ...
                        rec = _engine_record(p, "ERROR", error_text(exc), time.monotonic() - t0, self.name)
                    on_record(rec)
                try:
                    fut = done_q.get_nowait()
                except queue.Empty:
                    fut = None
            if timeout:
                now = time.monotonic()
                for key, (f, p, t0) in list(inflight.items()):
                    if now - t0 > 2 * timeout + grace:
                        del inflight[key]
                        f.cancel()
                        on_record(_engine_record(p, "TIMEOUT", f"time limit of {timeout:g} s exceeded (no result "
                                                 f"{now - t0:.1f} s after submission; cancelled)", now - t0,
                                                 self.name))


# --- the sweep ---------------------------------------------------------------------------


@dataclass
class SweepResult:
    """What :func:`run_sweep` did: the tasks, the latest record of each (those that
    have one), what ran now, timings, and the summary."""

    spec: object
    tasks: list
    records: dict
    ran: int
    to_run: int
    engine: str
    wall_seconds: float
    task_seconds: float
    slots: int
    interrupted: bool = False
    stray: int = 0
    bad_lines: int = 0
    summary: object = None
    files: list = field(default_factory=list)

    @property
    def overhead_per_task(self):
        """Engine seconds per task: (wall × parallel slots − Σ task seconds) / tasks run."""
        if not self.ran:
            return None
        return (self.wall_seconds * self.slots - self.task_seconds) / self.ran


class _Progress:
    """tqdm on stderr: tasks done, failures so far, time left; off when disabled."""

    def __init__(self, total, enabled):
        self.counts = Counter()
        self.bar = None
        if enabled and total:
            from tqdm import tqdm

            self.bar = tqdm(total=total, desc="sweep", unit="task", file=sys.stderr, dynamic_ncols=True,
                            smoothing=0.05)

    def update(self, rec):
        self.counts[rec["verdict"]] += 1
        if self.bar is not None:
            failed = sum(self.counts[v] for v in FAILED)
            shown = ", ".join(f"{v} {c}" for v, c in self.counts.most_common(4))
            self.bar.set_postfix_str(f"failed {failed}; {shown}", refresh=False)
            self.bar.update(1)

    def close(self):
        if self.bar is not None:
            self.bar.close()


def make_engine(workers=None, dask=None, client=None):
    """The engine for ``--workers`` / ``--dask`` (``workers = 0``: inline)."""
    workers = checked_workers(workers)
    if client is not None or dask is not None:
        return DaskEngine(dask, workers, client=client)
    if workers == 0:
        return InlineEngine()
    return LocalEngine(workers)


def run_sweep(spec, out_dir, *, workers=None, dask=None, client=None, only=None, timeout="spec",
              progress=False, plots=True, grace=None, echo=None, engine=None) -> SweepResult:
    """Run the tasks of ``spec`` not yet in ``out_dir`` (or those ``only`` selects),
    appending a line per task to ``out_dir/results.jsonl``, then write the summary.

    ``workers``: local processes (default: every core; 0: in this process);
    ``dask``: a scheduler address or ``'local'``; ``client``: an existing
    ``distributed.Client``; ``timeout``: seconds per task (default: the spec's);
    ``progress``: show a progress bar on stderr; ``echo``: called with lines to
    print (default: nothing).
    """
    from exact_khk.sweep.summary import summarise, write_summary

    say = echo or (lambda line: None)
    timeout = spec.timeout if timeout == "spec" else checked_timeout(timeout, "timeout")
    only = parse_only(only, spec.task) if isinstance(only, str) else only
    workers = checked_workers(workers)  # refused before the output folder exists
    out = prepare_folder(checked_out(out_dir))
    check_writable(out / RESULTS, "--out")
    tasks = spec.tasks()
    with _Lock(out):
        store = ResultStore(out)
        latest = store.latest()
        keys = {t.key for t in tasks}
        stray = sum(1 for k in latest if k not in keys)
        todo = select(tasks, latest, only)
        engine = engine or make_engine(workers, dask, client)
        if isinstance(engine, InlineEngine):
            _refuse_crash_inline(todo)
        meta = _read_meta(out)
        done_before = sum(1 for t in tasks if t.key in latest)
        say(f"sweep {spec.name}: {len(tasks)} {spec.task} tasks, {done_before} already done"
            + (f"; rerunning {len(todo)} ({', '.join(sorted(only))})" if only is not None else
               f"; {len(todo)} to run") + (f" (per-task limit {timeout:g} s)" if timeout else ""))
        if stray:
            say(f"note: {stray} records in {RESULTS} belong to no task of this spec (kept, not summarised)")
        if store.bad_lines:
            say(f"note: {store.bad_lines} unreadable lines in {RESULTS} skipped")
        run_info = {"started": now_iso(), "engine": engine.name, "only": sorted(only) if only else None,
                    "timeout": timeout, "to_run": len(todo)}
        t_start, task_seconds, task_cpu, ran, interrupted = time.monotonic(), 0.0, 0.0, 0, False
        c_start = time.process_time()
        bar = _Progress(len(todo), progress)
        store.open()
        try:
            if todo:
                with engine:
                    say(f"running on {engine.describe()}")
                    run_info["slots"] = engine.slots

                    def on_record(rec):
                        nonlocal task_seconds, task_cpu, ran
                        store.append(rec)
                        latest[rec["key"]] = rec
                        task_seconds += rec.get("seconds") or 0.0
                        task_cpu += rec.get("cpu_seconds") or 0.0
                        ran += 1
                        bar.update(rec)

                    engine.run([t.payload(timeout) for t in todo], on_record, timeout, grace)
        except KeyboardInterrupt:
            interrupted = True
            raise
        finally:
            bar.close()
            store.close()
            wall = time.monotonic() - t_start
            slots = getattr(engine, "slots", 1)
            run_info.update(finished=now_iso(), ran=ran, interrupted=interrupted, wall_seconds=round(wall, 3),
                            task_seconds=round(task_seconds, 3), task_cpu_seconds=round(task_cpu, 3),
                            parent_cpu_seconds=round(time.process_time() - c_start, 3),
                            load_average=list(os.getloadavg()) if hasattr(os, "getloadavg") else None,
                            slots=slots,
                            tasks_per_second=round(ran / wall, 3) if ran and wall > 0 else None,
                            overhead_seconds_per_task=round((wall * slots - task_seconds) / ran, 4)
                            if ran else None)
            if todo or not meta:
                meta = _meta(spec, len(tasks), meta, run_info if todo else None)
                write_atomic(out / META, json.dumps(meta, indent=1, ensure_ascii=False) + "\n", "--out")
        records = {t.key: latest[t.key] for t in tasks if t.key in latest}
        summary = summarise(spec, tasks, records)
        files = write_summary(summary, out, plots=plots)
    return SweepResult(spec, tasks, records, ran, len(todo), engine.describe(), wall, task_seconds,
                       getattr(engine, "slots", 1), interrupted, stray, store.bad_lines, summary, files)


def _refuse_crash_inline(tasks):
    """:class:`InputError` when a task to run in this process is a ``probe`` that kills
    the process running it (option ``crash``): in this process, that is the sweep itself."""
    seeds = [t.params["system"].get("seed") for t in tasks if t.params.get("task") == "probe"
             and t.params["system"].get("seed") in (t.params.get("options") or {}).get("crash", ())]
    if seeds:
        raise InputError(f"--workers: {len(seeds)} probe task(s) with 'crash' (system seeds "
                         f"{', '.join(map(str, seeds[:5]))}{', ...' if len(seeds) > 5 else ''}) kill the process "
                         f"running them, which with --workers 0 is this command; use --workers 1 or more")


def _read_meta(out: Path) -> dict:
    try:
        meta = json.loads((out / META).read_text(encoding="utf-8"))
        return meta if isinstance(meta, dict) else {}
    except (OSError, ValueError, RecursionError):  # unreadable: written anew
        return {}


def _meta(spec, ntasks, old: dict, run_info: dict) -> dict:
    runs = list(old.get("runs", [])) if isinstance(old.get("runs"), list) else []
    if run_info is not None:
        runs.append(run_info)
    return {"format": 1, "name": spec.name, "title": spec.title, "task": spec.task, "tasks": ntasks,
            "spec": {"file": spec.origin, "sha256": spec.digest, "text": spec.text},
            "runs": runs[-100:]}
