"""A study's trials as the sweep's workers see them: which count against the budget, which
belong to a worker on this machine that died (journal storage has no heartbeat), and a failed
or interrupted trial queued again as its retry."""

from __future__ import annotations

import os
import socket


def live_count(study) -> tuple[int, bool]:
    """(trials that count against the budget: all but failed ones, whether one is waiting)."""
    from optuna.trial import TrialState

    trials = study.get_trials(deepcopy=False)
    live = sum(t.state != TrialState.FAIL for t in trials)
    return live, any(t.state == TrialState.WAITING for t in trials)


def fail_dead_local_trials(study) -> None:
    """Journal storage has no heartbeat: a RUNNING trial of a worker on this machine whose
    process is gone is marked failed and its parameters queued again."""
    from optuna.trial import TrialState

    host = socket.gethostname()
    for t in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
        owner = str(t.user_attrs.get("worker", ""))
        name, _, pid = owner.rpartition(":")
        if name != host or not pid.isdigit() or _alive(int(pid)):
            continue
        study.tell(t.number, state=TrialState.FAIL)
        retry(study, t)


def retry(study, trial) -> None:
    """Queue a failed or interrupted trial's parameters again, marked as its retry."""
    attrs = {"retry_of": trial.number}
    if trial.user_attrs.get("baseline"):
        attrs["baseline"] = True
    study.enqueue_trial(trial.params, user_attrs=attrs)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
