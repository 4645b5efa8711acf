"""Sweeps: spec files, the local and Dask engines, resuming, failures, the summary."""

import json
import os
import pathlib
import signal
import subprocess
import sys
import threading
import time

import pytest

from exact_khk.cli.main import main
from exact_khk.errors import InputError
from exact_khk.sweep import (LocalEngine, ResultStore, load_spec, parse_spec, run_sweep, run_task,
                             task_key)
from exact_khk.sweep.tasks import TaskTimeout, time_limit

ROOT = pathlib.Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "sweep-lie-poisson.toml"
#: fields of a result line that depend on when and where it ran
RUN_FIELDS = ("seconds", "cpu_seconds", "worker", "finished")

CERTIFY = """
task = "certify"
timeout = 60
[system]
family = "lie-poisson"
n = "2-3"
seeds = "0-2"
[grid]
eps = ["1/10", "1/3"]
steps = 3
[options]
signs = "b0"
poisson_points = 1
"""


def probe_spec(seeds="0-5", sleep=0.0, timeout=30, **options):
    opts = "".join(f"{k} = {json.dumps(v)}\n" for k, v in options.items())
    return parse_spec(f'task = "probe"\ntimeout = {timeout}\n[system]\nfamily = "lie-poisson"\nn = 2\n'
                      f'seeds = "{seeds}"\n[options]\nsleep = {sleep}\n{opts}', origin="probe.toml")


def lines(out_dir):
    text = (pathlib.Path(out_dir) / "results.jsonl").read_text()
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def stable(records):
    """Result lines without the fields that depend on time and place, by key."""
    return {r["key"]: {k: v for k, v in r.items() if k not in RUN_FIELDS} for r in records}


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


# --- spec files -----------------------------------------------------------------------


def test_example_spec_expands():
    spec = load_spec(EXAMPLE)
    tasks = spec.tasks()
    assert len(tasks) == spec.count() == 20 and len({t.key for t in tasks}) == 20
    t = tasks[0]
    assert t.params == {"task": "certify", "system": {"family": "lie-poisson", "n": 2, "seed": 0},
                        "point": {"seed": 0}, "eps": "1/10", "arith": "flint", "steps": 6,
                        "options": {"poisson_points": 2, "signs": "b0"}}
    assert t.axes == {"n": 2, "seed": 0, "eps": "1/10"}
    json.dumps(t.payload(60))  # plain JSON


def test_keys_are_content_addresses():
    a = parse_spec(CERTIFY.replace('"1/10"', '"0.1"'), origin="a.toml").tasks()
    b = parse_spec(CERTIFY + "\n# a comment\n", origin="b.toml").tasks()
    assert [t.key for t in a] == [t.key for t in b]          # 0.1 is 1/10; comments do not matter
    c = parse_spec(CERTIFY.replace("poisson_points = 1", "poisson_points = 2"), origin="c.toml").tasks()
    assert not {t.key for t in a} & {t.key for t in c}       # options are parameters
    assert a[0].key == task_key(a[0].params)
    d = parse_spec(CERTIFY.replace('eps = ["1/10", "1/3"]', "eps = 0.1"), origin="d.toml").tasks()
    assert {t.key for t in d} < {t.key for t in a}           # a TOML float is the decimal it spells


BAD = [
    ("", "task: missing"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n[grid]\n'
     'eps = {start = "1/100", stop = "1/2", count = 1000001}\n',
     "grid.eps.count: expected an integer from 1 to 1,000,000, got 1000001"),
    ('task = "fly"\n', "task: unknown task 'fly'"),
    ('task = "certify"\ncolour = 1\n', "colour: unknown key"),
    ('task = "certify"\n', "system: missing table [system]"),
    ("task = [", "not valid TOML"),
    ('task = "certify"\nformat = 2\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n', "format:"),
    ('task = "certify"\ntimeout = -1\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n', "timeout:"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 1\nseeds = 0\n', "system.n: the Lie–Poisson family needs n >= 2"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = "2-x"\nseeds = 0\n', "system.n:"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = "5-2"\n', "system.seeds: '5-2': the range is empty"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\n', "system.seeds: missing"),
    ('task = "certify"\n[system]\nfamily = "toda"\nn = 2\nseeds = 0\n', "system.family: unknown family"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\ncatalogue = "x"\n', "system: give exactly one"),
    ('task = "certify"\n[system]\nfile = "no-such-file.toml"\n', "system.file: "),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n[grid]\neps = ["1/10", "0"]\n',
     "grid.eps[1]: the step size must be nonzero"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n[grid]\neps = ["abc"]\n',
     "grid.eps[0]: 'abc' is not a rational number"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n[grid]\nepsilon = 1\n',
     "grid.epsilon: unknown key"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n[grid]\narith = "quad"\n', "grid.arith:"),
    ('task = "scale"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n[grid]\narith = "flint"\n',
     "grid.arith: scale compares a floating or ball arithmetic"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n[grid]\nsteps = 0\n',
     "grid.steps: values must be >= 1"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n[options]\nsteps = 3\n',
     "options.steps: unknown option of task 'certify'"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n[options]\npoisson_points = 0\n',
     "options.poisson_points: expected a positive integer"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = "2-3"\nseeds = 0\n[options]\nsigns = ["-++"]\n',
     "options.signs[0]: '-++' is a pattern for n = 3"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n[options]\nclaims = ["integrals"]\n',
     "options.claims: applies to catalogue systems and system files only"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n[points]\nx0 = ["1", "2", "3"]\n',
     "points.x0: expected 4 coordinates, got 3"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n[points]\nseeds = 0\ndefault = true\n',
     "points: give one of seeds, x0 or default"),
    ('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n[points]\nwhere = 1\n',
     "points.where: unknown key"),
]


@pytest.mark.parametrize("text, fragment", BAD)
def test_malformed_specs_name_the_field(text, fragment):
    with pytest.raises(InputError) as info:
        parse_spec(text, origin="bad.toml")
    assert str(info.value).startswith("bad.toml: ")
    assert fragment in str(info.value)


def test_malformed_spec_on_the_command_line(capsys, tmp_path):
    spec = tmp_path / "bad.toml"
    spec.write_text('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 0\n[grid]\neps = "1/0"\n')
    code, out, err = run(capsys, "sweep", spec, "--out", tmp_path / "out")
    assert code == 2 and "grid.eps: '1/0' is not a rational number" in err and "bad.toml" in err
    assert not (tmp_path / "out").exists()                   # refused before anything is written
    code, _, err = run(capsys, "sweep", tmp_path / "none.toml", "--out", tmp_path / "out")
    assert code == 2 and "no such sweep spec file" in err
    code, _, err = run(capsys, "sweep", EXAMPLE, "--out", tmp_path / "out", "--workers", "-1")
    assert code == 2 and "--workers" in err
    # a typo such as 100000 would start a process per task: refused before anything runs
    code, _, err = run(capsys, "sweep", EXAMPLE, "--out", tmp_path / "out", "--workers", "100000")
    assert code == 2 and "--workers: 100000 is more than 4 per core" in err and not (tmp_path / "out").exists()
    (tmp_path / "file").write_text("")
    code, _, err = run(capsys, "sweep", EXAMPLE, "--out", tmp_path / "file", "--workers", "0")
    assert code == 5 and "not a folder" in err


# --- running ------------------------------------------------------------------------------


def test_run_task_is_plain_data_and_deterministic():
    task = parse_spec(CERTIFY, origin="s.toml").tasks()[3]
    a, b = run_task(task.payload()), run_task(json.loads(json.dumps(task.payload())))
    assert json.loads(json.dumps(a)) == a                   # JSON-compatible
    assert stable([a]) == stable([b])
    assert a["verdict"] in ("VALID", "INCONCLUSIVE", "SINGULAR") and a["error"] is None
    assert set(a) >= {"key", "params", "verdict", "detail", "figures", "error", "seconds", "cpu_seconds", "worker",
                      "finished", "versions"}


def test_run_task_keeps_the_callers_int_digit_limit():
    """A task lifts Python's int/str digit limit only while it runs (huge exact figures),
    and gives the caller its own setting back."""
    before = sys.get_int_max_str_digits()
    sys.set_int_max_str_digits(5000)
    try:
        run_task(parse_spec(CERTIFY, origin="s.toml").tasks()[0].payload())
        assert sys.get_int_max_str_digits() == 5000
    finally:
        sys.set_int_max_str_digits(before)


def test_local_and_dask_give_identical_results(capsys, tmp_path):
    distributed = pytest.importorskip("distributed")
    spec = tmp_path / "s.toml"
    spec.write_text(CERTIFY)
    code, out, _ = run(capsys, "sweep", spec, "--out", tmp_path / "local", "--workers", "2", "--no-plots")
    assert code == 0 and "12 certify tasks" in out and "verdicts:" in out
    local = lines(tmp_path / "local")
    assert len(local) == 12 and {r["worker"]["engine"] for r in local} == {"local"}
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, protocol="tcp",
                                  dashboard_address=None) as cluster:
        code, out, _ = run(capsys, "sweep", spec, "--out", tmp_path / "dask", "--dask", cluster.scheduler_address,
                           "--no-plots")
    assert code == 0 and "Dask" in out
    dask = lines(tmp_path / "dask")
    assert {r["worker"]["engine"] for r in dask} == {"dask"} and all("address" in r["worker"] for r in dask)
    assert stable(dask) == stable(local)
    summary = json.loads((tmp_path / "dask" / "summary.json").read_text())
    assert sum(summary["counts"].values()) == 12 and summary["grid"]["rows"] == "n"


def test_dask_records_errors_and_timeouts():
    distributed = pytest.importorskip("distributed")
    spec = probe_spec("0-3", timeout=1, fail=[1], slow=[2])
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        import tempfile

        with tempfile.TemporaryDirectory() as out:
            res = run_sweep(spec, out, client=client, plots=False)
            got = {r["params"]["system"]["seed"]: r for r in lines(out)}
    assert res.ran == 4 and {s: r["verdict"] for s, r in got.items()} == {0: "OK", 1: "ERROR", 2: "TIMEOUT", 3: "OK"}
    assert got[1]["error"] == "RuntimeError: probe failure at seed 1"
    assert got[2]["error"] == "time limit of 1 s exceeded" and got[2]["seconds"] < 10


def test_errors_and_timeouts_are_recorded_and_the_sweep_completes(tmp_path):
    # seed 1 raises, seed 2 sleeps (stopped inside the worker), seed 3 blocks in C (worker killed)
    spec = probe_spec("0-7", timeout=1, fail=[1], slow=[2], hang=[3])
    t0 = time.monotonic()
    res = run_sweep(spec, tmp_path, engine=LocalEngine(2), grace=1.0, plots=False)
    assert time.monotonic() - t0 < 25
    got = {r["params"]["system"]["seed"]: r for r in lines(tmp_path)}
    assert len(lines(tmp_path)) == 8 and res.ran == 8
    assert {s: r["verdict"] for s, r in got.items()} == {0: "OK", 1: "ERROR", 2: "TIMEOUT", 3: "TIMEOUT", 4: "OK",
                                                         5: "OK", 6: "OK", 7: "OK"}
    assert got[1]["error"] == "RuntimeError: probe failure at seed 1"
    assert got[2]["error"] == "time limit of 1 s exceeded"
    assert "killed" in got[3]["error"]
    assert res.summary.counts == {"OK": 5, "TIMEOUT": 2, "ERROR": 1}
    assert "rerun them with --only failed" in res.summary.text()
    # --only failed reruns exactly the three failures
    res = run_sweep(spec, tmp_path, engine=LocalEngine(2), only="failed", grace=1.0, plots=False)
    assert res.ran == 3 and len(lines(tmp_path)) == 11
    assert sorted(r["params"]["system"]["seed"] for r in lines(tmp_path)[8:]) == [1, 2, 3]
    assert res.summary.counts == {"OK": 5, "TIMEOUT": 2, "ERROR": 1}


def test_a_task_that_kills_its_worker_is_recorded(tmp_path):
    spec = probe_spec("0-5", sleep=0.1, crash=[2])
    res = run_sweep(spec, tmp_path, engine=LocalEngine(2), plots=False)
    got = {r["params"]["system"]["seed"]: r for r in lines(tmp_path)}
    assert len(lines(tmp_path)) == 6 and res.summary.counts == {"OK": 5, "ERROR": 1}
    assert got[2]["verdict"] == "ERROR" and "worker process died" in got[2]["error"]


def test_a_crash_probe_in_this_process_is_refused(tmp_path):
    """``--workers 0`` runs tasks in the command's own process: a probe that kills the process
    running it is refused before anything runs (one line, exit 2), not a silent exit 137."""
    spec = tmp_path / "probe.toml"
    spec.write_text('task = "probe"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = "0-3"\n'
                    '[options]\ncrash = [2]\n')
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "exact_khk", "sweep", str(spec), "--out", str(out), "--workers",
                           "0", "--no-plots"], capture_output=True, text=True, timeout=120)
    err = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(err) == 1, (proc.returncode, proc.stderr)
    assert "--workers" in err[0] and "crash" in err[0] and "seeds 2" in err[0]
    assert not (out / "results.jsonl").exists() or not lines(out)
    # without the crashing seed the same sweep runs in this process
    spec.write_text(spec.read_text().replace("crash = [2]", "crash = [7]"))
    res = run_sweep(load_spec(spec), out, workers=0, plots=False)
    assert res.ran == 4 and res.summary.counts == {"OK": 4}


def test_results_lines_are_written_at_once_and_synced_in_batches(tmp_path, monkeypatch):
    """Every line reaches the file (the OS) when append returns — what a kill -9 cannot take
    back — while fsync runs in batches: far fewer than one per line, and once more at close."""
    import exact_khk.sweep.run as run_mod

    synced = []
    real = os.fsync
    monkeypatch.setattr(run_mod.os, "fsync", lambda fd: (synced.append(fd), real(fd)))
    store = ResultStore(tmp_path, sync_seconds=0.05).open()
    for i in range(200):
        store.append({"key": f"k{i}", "verdict": "OK"})
        assert (tmp_path / "results.jsonl").read_bytes().count(b"\n") == i + 1
    t0 = time.monotonic()
    while not synced and time.monotonic() - t0 < 30:  # the background sync comes within the window
        time.sleep(0.01)
    background = len(synced)
    assert 1 <= background < 200
    store.close()
    assert len(synced) == background + 1
    assert [r["key"] for r in ResultStore(tmp_path).read()] == [f"k{i}" for i in range(200)]


class _BreaksBeforeSubmit(LocalEngine):
    """A local engine whose pool breaks between a wait and the next submission: before
    submission ``at`` one worker is killed and the pool is seen broken, so that submission
    raises BrokenProcessPool (the race a worker that dies at that moment wins), or with
    ``oserror`` the OSError Python 3.11's pool can raise then from its closed wake-up pipe."""

    def __init__(self, workers, at=3, oserror=False):
        super().__init__(workers)
        self.at, self.oserror, self.calls = at, oserror, 0

    def _start(self):
        super()._start()
        real, engine = self._pool, self

        class Pool:
            def __getattr__(self, name):
                return getattr(real, name)

            def submit(self, fn, *args):
                engine.calls += 1
                if engine.calls == engine.at:
                    next(iter(real._processes.values())).kill()
                    deadline = time.monotonic() + 30
                    while not real._broken and time.monotonic() < deadline:
                        time.sleep(0.01)
                    assert real._broken
                    if engine.oserror:
                        raise OSError("handle is closed")
                return real.submit(fn, *args)

        self._pool = Pool()


@pytest.mark.parametrize("oserror", [False, True])
def test_a_pool_that_breaks_before_a_submission_reruns_its_tasks(tmp_path, oserror):
    """No task dies here, but the pool breaks before a submission: every task still gets its
    record (OK), none is lost or run twice into the results."""
    engine = _BreaksBeforeSubmit(2, oserror=oserror)
    res = run_sweep(probe_spec("0-5", sleep=0.5), tmp_path, engine=engine, plots=False)
    assert engine.calls > 6  # the broken submission and the reruns happened
    assert sorted(r["params"]["system"]["seed"] for r in lines(tmp_path)) == [0, 1, 2, 3, 4, 5]
    assert res.summary.counts == {"OK": 6}


def test_a_pool_that_refuses_its_first_task_stops_the_sweep(tmp_path):
    """A pool broken before it took any task is not restarted for ever: one error naming it."""
    with pytest.raises(RuntimeError, match="the local worker pool refuses tasks .*OSError"):
        run_sweep(probe_spec("0-1"), tmp_path, engine=_BreaksBeforeSubmit(2, at=1, oserror=True), plots=False)


def test_inline_errors_from_the_mathematics(tmp_path):
    spec = parse_spec('task = "certify"\n[system]\nfamily = "lie-poisson"\nn = 4\nseeds = 1\n[options]\n'
                      'prove = true\n', origin="p.toml")
    res = run_sweep(spec, tmp_path, workers=0, plots=False)
    (rec,) = lines(tmp_path)
    assert rec["verdict"] == "ERROR" and rec["error"].startswith("InputError: prove: symbolic proofs are offered up to dimension 4")
    assert res.summary.counts == {"ERROR": 1}


def test_time_limit_in_main_thread_and_in_other_threads():
    with pytest.raises(TaskTimeout):
        with time_limit(0.2):
            time.sleep(5)
    caught = []

    def body():
        try:
            with time_limit(0.2):
                while True:
                    sum(range(1000))
        except TaskTimeout:
            caught.append(True)

    th = threading.Thread(target=body)
    th.start()
    th.join(10)
    assert caught == [True] and not th.is_alive()
    with time_limit(5):  # a body that finishes leaves nothing behind
        pass
    time.sleep(0.05)


def _start_cli(spec, out, workers=2):
    return subprocess.Popen([sys.executable, "-m", "exact_khk", "sweep", str(spec), "--out", str(out),
                             "--workers", str(workers), "--no-plots"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)


def _wait_for_lines(out, count, proc, limit=60):
    path = pathlib.Path(out) / "results.jsonl"
    t0 = time.monotonic()
    while time.monotonic() - t0 < limit:
        if path.exists() and path.read_text().count("\n") >= count:
            return
        if proc.poll() is not None:
            raise AssertionError(f"the sweep ended early: {proc.communicate()}")
        time.sleep(0.05)
    raise AssertionError("no progress")


@pytest.mark.parametrize("how", ["kill", "ctrl-c"])
def test_resume_after_interruption(tmp_path, capsys, how):
    spec = tmp_path / "probe.toml"
    spec.write_text('task = "probe"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = "0-29"\n'
                    '[options]\nsleep = 0.15\n')
    out = tmp_path / "out"
    proc = _start_cli(spec, out)
    _wait_for_lines(out, 6, proc)
    if how == "kill":  # the whole process group, workers included, without warning
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(20)
        with open(out / "results.jsonl", "a") as fh:  # a line cut short by the crash
            fh.write('{"format":1,"key":"abc')
    else:
        os.killpg(proc.pid, signal.SIGINT)
        assert proc.wait(30) == 130
        err = proc.stderr.read().decode().strip().splitlines()
        assert len(err) == 1 and err[0].startswith("exact-khk: interrupted:") and "resumes" in err[0], err
    before = ResultStore(out).read()
    assert 6 <= len(before) < 30
    code, text, _ = run(capsys, "sweep", spec, "--out", out, "--workers", "2", "--no-plots")
    assert code == 0 and f"{len(before)} already done" in text
    after = lines(out)
    keys = [r["key"] for r in after]
    assert len(keys) == len(set(keys)) == 30                # no task done twice, none lost
    assert after[:len(before)] == before                    # what was done is untouched
    assert {t.key for t in load_spec(spec).tasks()} == set(keys)
    code, text, _ = run(capsys, "sweep", spec, "--out", out, "--workers", "2", "--no-plots")
    assert code == 0 and "30 already done; 0 to run" in text and len(lines(out)) == 30


def test_ctrl_c_on_a_local_dask_cluster_is_one_line_per_message(tmp_path):
    """Ctrl-C (SIGINT to the whole process group, as a terminal sends it) during a sweep on
    ``--dask local``: status 130, the one line of the local engine, no traceback from the
    worker processes (they start with SIGINT ignored), finished tasks kept."""
    spec = tmp_path / "probe.toml"
    spec.write_text('task = "probe"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = "0-29"\n'
                    '[options]\nsleep = 0.3\n')
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "exact_khk", "sweep", str(spec), "--out", str(out), "--dask",
                             "local", "--workers", "2", "--no-plots"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    _wait_for_lines(out, 2, proc, limit=120)
    os.killpg(proc.pid, signal.SIGINT)
    assert proc.wait(60) == 130
    err = proc.stderr.read().decode()
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err[-2000:]
    assert err.startswith("exact-khk: interrupted:") and "resumes" in err
    assert 2 <= len(ResultStore(out).read()) < 30


def test_one_sweep_per_folder(tmp_path):
    spec = probe_spec("0-1")
    from exact_khk.sweep.run import _Lock
    from exact_khk.errors import OutputError

    with _Lock(tmp_path):
        with pytest.raises(OutputError, match="another sweep is writing"):
            run_sweep(spec, tmp_path, workers=0)


# --- other tasks, systems, the summary ---------------------------------------------------------


EULER = """
format = 1
name = "euler-top-example"
variables = ["x1", "x2", "x3"]
claims = ["reversibility", "integrals"]
[field]
x1 = "x2*x3"
x2 = "-2*x3*x1"
x3 = "3*x1*x2"
[integrals]
I1 = "(1 - eps**2*(-2)*3*x1**2)/(1 - eps**2*1*3*x2**2)"
[defaults]
x0 = ["1", "2", "3"]
eps = "1/10"
"""


def test_system_file_sweep_ships_the_system(tmp_path):
    (tmp_path / "euler.toml").write_text(EULER)
    (tmp_path / "spec.toml").write_text('task = "certify"\n[system]\nfile = "euler.toml"\n[points]\nseeds = "0-1"\n'
                                        '[grid]\neps = ["1/10", "1/20"]\nsteps = 3\n')
    spec = load_spec(tmp_path / "spec.toml")
    tasks = spec.tasks()
    assert len(tasks) == 4 and tasks[0].params["system"]["name"] == "euler-top-example"
    assert tasks[0].axes == {"point": 0, "eps": "1/10"}
    (tmp_path / "euler.toml").unlink()                      # the worker never reads the file
    res = run_sweep(spec, tmp_path / "out", workers=0, plots=False)
    recs = lines(tmp_path / "out")
    assert len(recs) == 4 and all(r["error"] is None and r["figures"]["false"] == 0 for r in recs)
    # (INCONCLUSIVE: this integral's eps -> 0 limit is the constant 1, so that control cannot fail)
    assert set(res.summary.counts) <= {"VALID", "INCONCLUSIVE"}
    (tmp_path / "spec.toml").write_text('task = "certify"\n[system]\nfile = "euler.toml"\n[points]\nseeds = "same"\n')
    (tmp_path / "euler.toml").write_text(EULER)
    with pytest.raises(InputError, match="points.seeds: 'same'"):
        load_spec(tmp_path / "spec.toml")


def test_orbit_and_scale_tasks(tmp_path):
    orbit = parse_spec('task = "orbit"\n[system]\nfamily = "lie-poisson"\nn = 3\nseeds = "1-2"\n[grid]\nsteps = 8\n'
                       'arith = ["flint", "float"]\n', origin="o.toml")
    res = run_sweep(orbit, tmp_path / "o", workers=0, plots=False)
    recs = lines(tmp_path / "o")
    exact = [r for r in recs if r["params"]["arith"] == "flint"]
    assert {r["verdict"] for r in recs} <= {"OK", "SINGULAR"} and exact
    ok = [r for r in exact if r["verdict"] == "OK"]
    assert ok and all(len(r["figures"]["heights"]) == 9 and 0.5 < r["figures"]["height_growth_exponent"] < 3
                      for r in ok)
    assert "height_growth_exponent" in res.summary.text()
    scale = parse_spec('task = "scale"\n[system]\nfamily = "lie-poisson"\nn = 3\nseeds = 1\n[grid]\nsteps = 6\n'
                       'eps = ["1/10", "1/2"]\narith = ["float", "mp:113"]\n', origin="s.toml")
    res = run_sweep(scale, tmp_path / "s", workers=0, plots=False)
    recs = lines(tmp_path / "s")
    assert len(recs) == 4 and all(r["verdict"] in ("OK", "WARNED", "SINGULAR") for r in recs)
    assert all("final_error_log10" in r["figures"] for r in recs if r["verdict"] == "OK")


def test_diagnostics_tasks(tmp_path):
    """degrees and find-integrals as sweep tasks: the Lie–Poisson family's degrees grow
    linearly with the field f and the associated g; the catalogue's Kahan Lotka–Volterra
    map grows exponentially (λ = 2); integrals are found (and verified) for f."""
    spec = parse_spec('task = "degrees"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = "1-2"\n[grid]\n'
                      'steps = 14\n[options]\nfield = "g"\n', origin="d.toml")
    run_sweep(spec, tmp_path / "d", workers=0, plots=False)
    recs = lines(tmp_path / "d")
    assert len(recs) == 2 and {r["verdict"] for r in recs} == {"OK"}
    assert {(r["figures"]["growth"], r["figures"]["polynomial_degree"]) for r in recs} == {("polynomial", 1)}
    assert {tuple(r["figures"]["routes"]) for r in recs} == {("polynomials",)}  # dimension 4
    lv = parse_spec('task = "degrees"\n[system]\ncatalogue = "lotka-volterra"\n[grid]\nsteps = 10\n',
                    origin="lv.toml")
    run_sweep(lv, tmp_path / "lv", workers=0, plots=False)
    (rec,) = lines(tmp_path / "lv")
    assert rec["figures"]["growth"] == "exponential" and rec["figures"]["dynamical_degree"] == 2.0
    ints = parse_spec('task = "find-integrals"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 1\n',
                      origin="i.toml")
    run_sweep(ints, tmp_path / "i", workers=0, plots=False)
    (rec,) = lines(tmp_path / "i")
    assert rec["verdict"] == "FOUND" and rec["figures"]["verified"] >= 2 and rec["figures"]["independent"] == 2
    with pytest.raises(InputError, match="exact"):
        parse_spec('task = "degrees"\n[system]\nfamily = "lie-poisson"\nn = 2\nseeds = 1\n[grid]\narith = "float"\n',
                   origin="x.toml").tasks()


def test_summary_files_and_plots(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    spec = tmp_path / "p.toml"
    spec.write_text('task = "probe"\n[system]\nfamily = "lie-poisson"\nn = "2-4"\nseeds = "0-3"\n[grid]\n'
                    'eps = ["1/10", "1/5"]\n[options]\nfail = [2]\n')
    code, out, _ = run(capsys, "sweep", spec, "--out", tmp_path / "out", "--workers", "0")
    assert code == 0
    assert "verdicts: OK 18, ERROR 6" in out and "OK tasks against n and eps:" in out
    for name in ("results.jsonl", "sweep.json", "summary.txt", "summary.json", "tasks.csv", "verdicts.png",
                 "time.png", "figures.png"):
        assert (tmp_path / "out" / name).stat().st_size > 0, name
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["grid"]["cells"][0] == [[3, 4], [3, 4]]   # n = 2: OK in 3 of 4 seeds, at both eps
    assert [lv["value"] for lv in summary["by_axis"]["n"]] == [2, 3, 4]
    assert len(summary["failures"]) == 6
    csv_lines = (tmp_path / "out" / "tasks.csv").read_text().splitlines()
    assert len(csv_lines) == 25 and csv_lines[0] == ("key,n,eps,seed,verdict,seconds,figure:eps,"
                                                  "figure:n,figure:seed,value,error,detail")
    meta = json.loads((tmp_path / "out" / "sweep.json").read_text())
    assert meta["tasks"] == 24 and meta["runs"][-1]["ran"] == 24 and "task = \"probe\"" in meta["spec"]["text"]
    code, out, _ = run(capsys, "sweep", spec, "--out", tmp_path / "out", "--dry-run", "--only", "failed")
    assert code == 0 and "24 probe tasks, 24 done, 6 would run" in out
    code, out, _ = run(capsys, "sweep", spec, "--out", tmp_path / "out", "--summary", "--no-plots")
    assert code == 0 and "verdicts: OK 18, ERROR 6" in out and "already done" not in out
    # --only names verdicts: an unknown one, or one this task never gives, selects nothing: refused
    for only, message in (("bogus", "unknown verdict 'bogus'"), ("valid", "probe tasks never give VALID"),
                          ("failed,found", "probe tasks never give FOUND")):
        code, _, err = run(capsys, "sweep", spec, "--out", tmp_path / "out", "--only", only)
        assert code == 2 and message in err, (only, err)
        code, _, err = run(capsys, "sweep", spec, "--out", tmp_path / "out", "--dry-run", "--only", only)
        assert code == 2 and message in err, (only, err)
    assert ResultStore(tmp_path / "out").latest() and len((tmp_path / "out" / "results.jsonl").read_text()
                                                          .splitlines()) == 24  # nothing ran


def test_one_table_of_verdicts():
    """Every verdict a task or the engine gives is in VERDICTS, which orders and colours the
    summaries; registering a kind with another verdict is refused (negative control)."""
    from exact_khk.sweep.summary import COLORS, VERDICT_ORDER
    from exact_khk.sweep.tasks import ENGINE_VERDICTS, FAILED, TASKS, VERDICTS, TaskKind, register

    given = {v for kind in TASKS.values() for v in (*kind.verdicts, kind.ok)} | set(ENGINE_VERDICTS) | set(FAILED)
    assert given == set(VERDICTS) and len(set(VERDICTS)) == len(VERDICTS)
    assert VERDICT_ORDER[:-1] == VERDICTS and set(COLORS) == set(VERDICT_ORDER)
    with pytest.raises(ValueError, match="MAYBE"):
        register(TaskKind("bogus-kind", lambda inp: {}, "never registered", verdicts=("OK", "MAYBE")))
    assert "bogus-kind" not in TASKS
