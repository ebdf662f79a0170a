"""bipedal sweep: workers sharing a journal file or a real PostgreSQL server, a killed worker's
trial retried, pruning, and bad input. Trials are tiny (a few hundred steps)."""

import csv
import glob
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import optuna
import pytest
import yaml

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.sweep import DEFINITION, SweepSettings, run_worker
from bipedal_cli.sweep_space import base_params, load_space, validate_space

from .conftest import tiny_dict
from .test_cli import run_cli

SPACE = {
    "agent.lr": {"type": "float", "low": 1.0e-4, "high": 1.0e-3, "log": True},
    "agent.tau": {"type": "categorical", "choices": [0.005, 0.01, 0.02]},
}


@pytest.fixture
def sweep_files(tmp_path):
    config = tmp_path / "tiny.yaml"
    config.write_text(yaml.safe_dump(tiny_dict(eval_every=100, warmup_steps=50)))
    space = tmp_path / "space.yaml"
    space.write_text(yaml.safe_dump(SPACE))
    return config, space


def worker(tmp_path, config, space, study, trials, steps=200, storage=None, extra=()):
    args = [sys.executable, "-m", "bipedal_cli", "sweep", "--config", str(config)]
    args += ["--space", str(space), "--study", study, "--trials", str(trials)]
    args += ["--steps-per-trial", str(steps), *extra]
    if storage:
        args += ["--storage", storage]
    return subprocess.Popen(
        args, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )


def finish(proc, timeout=300):
    out, err = proc.communicate(timeout=timeout)
    assert proc.returncode == 0, err[-2000:]
    return out


def trials_of(study, storage):
    return optuna.load_study(study_name=study, storage=storage).get_trials(deepcopy=False)


def check_two_workers(trials, budget):
    states = [t.state for t in trials]
    numbers = sorted(t.number for t in trials)
    assert numbers == list(range(budget)), numbers  # none duplicated, none lost
    finished = (optuna.trial.TrialState.COMPLETE, optuna.trial.TrialState.PRUNED)
    assert all(s in finished for s in states), states
    pids = {t.user_attrs["worker"] for t in trials}
    assert len(pids) == 2, pids  # both workers ran trials


def in_process(tmp_path, study, trials, steps, base=None, **settings):
    """Settings of a tiny in-process study in ``tmp_path/sweeps`` over :data:`SPACE`."""
    return SweepSettings(
        study=study,
        base=base or config_from_dict(tiny_dict(eval_every=100, warmup_steps=50)),
        space=validate_space(SPACE, "test"),
        trials=trials,
        steps_per_trial=steps,
        root=tmp_path / "sweeps",
        **settings,
    )


def trial_metrics(tmp_path, study, number=0):
    path = tmp_path / "sweeps" / study / f"trial-{number:04d}" / "metrics.csv"
    return list(csv.DictReader(open(path)))


def journal(tmp_path, study):
    path = tmp_path / "sweeps" / study / "journal.log"
    return optuna.storages.JournalStorage(optuna.storages.journal.JournalFileBackend(str(path)))


def test_two_workers_on_one_journal_file_share_the_budget_exactly(tmp_path, sweep_files):
    procs = [worker(tmp_path, *sweep_files, "shared", 5) for _ in range(2)]
    for p in procs:
        finish(p)
    trials = trials_of("shared", journal(tmp_path, "shared"))
    check_two_workers(trials, 5)
    for t in trials:  # every trial is an ordinary run directory
        run = tmp_path / "sweeps" / "shared" / f"trial-{t.number:04d}"
        assert (run / "state.pt").exists() and (run / "metrics.csv").exists()
        assert load_checkpoint(run / "policy.pt")["meta"]["steps"] in (100, 200)


# ------------------------------------------------------------------------- PostgreSQL


def _pg_bin(name):
    found = shutil.which(name)
    if found:
        return found
    hits = sorted(glob.glob(f"/usr/lib/postgresql/*/bin/{name}"))
    return hits[-1] if hits else None


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def postgres_url():
    """A real PostgreSQL server in a temporary directory on 127.0.0.1, as a non-root user."""
    initdb, pg_ctl = _pg_bin("initdb"), _pg_bin("pg_ctl")
    if not (initdb and pg_ctl):
        pytest.skip(
            "PostgreSQL server binaries (initdb, pg_ctl) not installed: apt install postgresql"
        )
    as_user = []
    data = Path(tempfile.mkdtemp(prefix="bipedal-pg-", dir="/tmp"))
    if os.geteuid() == 0:  # initdb refuses root: run the server as nobody
        as_user = ["runuser", "-u", "nobody", "--"]
        shutil.chown(data, "nobody")
    data.chmod(0o755)
    port = _free_port()
    run = lambda *a: subprocess.run([*as_user, *a], check=True, capture_output=True, text=True)  # noqa: E731
    run(initdb, "-D", str(data / "db"), "-A", "trust", "-U", "postgres", "--no-sync")
    opts = f"-p {port} -k {data} -c listen_addresses=127.0.0.1 -c fsync=off"
    run(pg_ctl, "-D", str(data / "db"), "-o", opts, "-l", str(data / "log"), "-w", "start")
    try:
        url = f"postgresql+psycopg://postgres@127.0.0.1:{port}/postgres"
        yield url
    finally:
        subprocess.run([*as_user, pg_ctl, "-D", str(data / "db"), "-m", "immediate", "stop"])
        shutil.rmtree(data, ignore_errors=True)


def test_two_workers_started_together_on_postgresql(tmp_path, sweep_files, postgres_url):
    """Both try to create the study at the same moment: one creates, the other joins."""
    procs = [worker(tmp_path, *sweep_files, "pg", 5, storage=postgres_url) for _ in range(2)]
    for p in procs:
        finish(p)
    check_two_workers(trials_of("pg", postgres_url), 5)


def _kill_mid_trial(tmp_path, sweep_files, study, storage, extra=()):
    """Start a worker, SIGKILL it while its first trial trains, then run a second worker."""
    first = worker(tmp_path, *sweep_files, study, 1, steps=1000, storage=storage, extra=extra)
    metrics = tmp_path / "sweeps" / study / "trial-0000" / "metrics.csv"
    deadline = time.time() + 120
    while time.time() < deadline and not (metrics.exists() and metrics.stat().st_size > 300):
        time.sleep(0.2)
    assert metrics.exists(), first.communicate()[1]
    first.send_signal(signal.SIGKILL)
    first.wait(timeout=30)
    time.sleep(3)  # past the heartbeat's grace period
    finish(worker(tmp_path, *sweep_files, study, 1, steps=1000, storage=storage, extra=extra))


def _check_retried(trials):
    by_number = {t.number: t for t in trials}
    assert by_number[0].state == optuna.trial.TrialState.FAIL
    retries = [t for t in trials if t.number != 0]
    assert len(retries) == 1 and retries[0].state == optuna.trial.TrialState.COMPLETE
    assert retries[0].params == by_number[0].params  # the same parameters run again


def test_a_killed_workers_trial_fails_and_reruns_on_postgresql(tmp_path, sweep_files, postgres_url):
    _kill_mid_trial(tmp_path, sweep_files, "kill-pg", postgres_url, ("--heartbeat", "1"))
    trials = trials_of("kill-pg", postgres_url)
    _check_retried(trials)
    assert trials[-1].system_attrs["failed_trial"] == 0  # Optuna's retry callback made it


def test_a_killed_workers_trial_fails_and_reruns_on_a_journal_file(tmp_path, sweep_files):
    _kill_mid_trial(tmp_path, sweep_files, "kill-journal", None)
    _check_retried(trials_of("kill-journal", journal(tmp_path, "kill-journal")))


# ---------------------------------------------------------------------------- pruning


def test_a_trial_trailing_the_median_is_pruned_and_its_run_stops(tmp_path):
    settings = in_process(tmp_path, "prune", 4, 400, pruner_startup=3, pruner_warmup=0)
    (tmp_path / "sweeps" / "prune").mkdir(parents=True)
    storage = journal(tmp_path, "prune")
    study = optuna.create_study(study_name="prune", storage=storage)
    study.set_user_attr(DEFINITION, settings.definition())
    for i in range(3):  # three finished trials whose evaluations scored 300 at every step
        study.add_trial(
            optuna.create_trial(
                params={"agent.lr": 3e-4, "agent.tau": 0.005},
                distributions={
                    "agent.lr": optuna.distributions.FloatDistribution(1e-4, 1e-3, log=True),
                    "agent.tau": optuna.distributions.CategoricalDistribution([0.005, 0.01, 0.02]),
                },
                value=1000.0 + i,
                intermediate_values={s: -300.0 for s in (100, 200, 300, 400)},
            )
        )
    result = run_worker(settings, lambda n: None)
    assert result.ran == [3]
    trial = study.get_trials()[3]
    assert trial.state == optuna.trial.TrialState.PRUNED
    assert list(trial.intermediate_values) == [100]  # stopped at its first evaluation
    state = load_checkpoint(tmp_path / "sweeps" / "prune" / "trial-0003" / "state.pt")
    assert state["counters"]["step"] == 100


def test_the_first_trial_is_the_base_config_so_the_search_has_a_baseline(tmp_path):
    base = config_from_dict(tiny_dict(eval_every=100, warmup_steps=50))
    space = validate_space(SPACE, "test")
    assert base_params(base, space) == {"agent.lr": base.agent.lr, "agent.tau": base.agent.tau}
    outside = validate_space(
        {**SPACE, "agent.gamma": {"type": "float", "low": 0.5, "high": 0.9}}, "t"
    )
    assert base_params(base, outside) is None  # gamma 0.98 lies outside: no baseline trial
    steps = validate_space(
        {"agent.n_quantiles": {"type": "int", "low": 10, "high": 40, "step": 4}}, "t"
    )
    assert base_params(config_from_dict({"agent": {"n_quantiles": 25}}), steps) is None  # off-step
    for study, baseline in (("with", True), ("without", False)):
        settings = in_process(tmp_path, study, 2, 100, base, baseline=baseline)
        assert run_worker(settings, lambda n: None).ran == [0, 1]
        first, second = trials_of(study, journal(tmp_path, study))
        assert (first.params == base_params(base, space)) is baseline
        assert first.user_attrs.get("baseline", False) is baseline
        assert "baseline" not in second.user_attrs and second.params != first.params


def test_a_solved_trial_records_the_evaluation_and_the_test_that_solved_it(tmp_path):
    data = tiny_dict(eval_every=100, warmup_steps=50, solved_threshold=-1e6, solved_episodes=2)
    settings = in_process(tmp_path, "solve", 1, 300, config_from_dict(data))
    assert run_worker(settings, lambda n: None).ran == [0]
    (trial,) = trials_of("solve", journal(tmp_path, "solve"))
    rows = trial_metrics(tmp_path, "solve")
    (periodic,) = [r for r in rows if r["kind"] == "eval"]  # solved at the first evaluation
    (test,) = [r for r in rows if r["kind"] == "full_eval"]
    assert trial.value == trial.user_attrs["env_steps"] == int(periodic["env_steps"]) == 100
    assert trial.user_attrs["best_eval"] == pytest.approx(float(periodic["return"]))
    assert trial.user_attrs["test"] == pytest.approx(float(test["return"]))
    assert trial.intermediate_values == {100: pytest.approx(-float(periodic["return"]))}


def test_the_pruner_sees_each_trials_best_evaluation_so_far(tmp_path):
    settings = in_process(tmp_path, "best", 1, 400)
    run_worker(settings, lambda n: None)
    (trial,) = trials_of("best", journal(tmp_path, "best"))
    rows = trial_metrics(tmp_path, "best")
    evals = [float(r["return"]) for r in rows if r["kind"] == "eval"]
    best_so_far = [-max(evals[: i + 1]) for i in range(len(evals))]
    assert len(evals) == 4 and len(set(evals)) > 1
    assert list(trial.intermediate_values.values()) == pytest.approx(best_so_far, abs=1e-3)


# -------------------------------------------------------------------------- bad input


def test_bad_search_spaces_name_the_parameter(tmp_path):
    from bipedal_cli.errors import UserError

    cases = [
        ({"agent.lrr": {"type": "float", "low": 1, "high": 2}}, "agent.lrr"),
        ({"agent.lr": {"type": "float", "low": 2, "high": 1}}, "low < high"),
        ({"agent.lr": {"type": "float", "low": 0, "high": 1, "log": True}}, "low > 0"),
        ({"agent.batch_size": {"type": "float", "low": 1, "high": 2}}, "use type int"),
        ({"agent.lr": {"type": "normal"}}, "float, int or categorical"),
        ({"agent.tau": {"type": "categorical", "choices": ["x"]}}, "not a float"),
    ]
    for space, needle in cases:
        with pytest.raises(UserError, match=needle):
            validate_space(space, "space.yaml")
    assert set(load_space(None)) >= {"agent.gamma", "agent.lr", "agent.batch_size", "agent.tau"}


def test_sweep_bad_input_is_one_line_and_leaves_the_study_intact(
    tmp_path, sweep_files, capsys, monkeypatch
):
    config, space = sweep_files
    monkeypatch.chdir(tmp_path)

    def sweep(*extra):
        args = ["sweep", "--config", config, "--study", "s", "--trials", 1]
        return run_cli([*args, "--steps-per-trial", 100, *extra], capsys)

    status, _, err = sweep("--space", space)
    assert status == 0, err
    log = tmp_path / "sweeps" / "s" / "journal.log"
    before = log.read_bytes()
    other = tmp_path / "other.yaml"
    other.write_text(yaml.safe_dump({"agent.lr": SPACE["agent.lr"]}))
    unknown = tmp_path / "unknown.yaml"
    unknown.write_text(yaml.safe_dump({"agent.nope": SPACE["agent.lr"]}))
    cases = [
        (["--space", other], "another space"),
        (["--space", unknown], "agent.nope"),
        (
            ["--space", space, "--storage", "postgresql+psycopg://u:secret@127.0.0.1:1/x"],
            "cannot open",
        ),
        (["--space", space, "--storage", "redis://127.0.0.1"], "expected a journal file"),
        (["--space", space, "--pruner-startup", "-1"], "--pruner-startup -1"),
        (["--space", space, "--pruner-warmup", "-5"], "--pruner-warmup -5"),
        (["--space", space, "--sampler-startup", "-1"], "--sampler-startup -1"),
    ]
    for extra, needle in cases:
        status, _, err = sweep(*extra)
        lines = err.strip().splitlines()
        assert status == 2 and len(lines) == 1 and needle in lines[0], err
        assert "secret" not in err
    assert log.read_bytes() == before
    status, out, err = run_cli(["sweep", "show", "s", "--best-config", tmp_path / "b.yaml"], capsys)
    assert status == 0, err
    best = config_from_dict(yaml.safe_load((tmp_path / "b.yaml").read_text()))
    assert best.train.total_steps == 100 and best.agent.batch_size == 16
    assert (tmp_path / "sweeps" / "s" / "history.png").stat().st_size > 1000
