"""The trade-off's accuracies are tasks of the study runner: the same table in this process and on workers
(issue 21: the trade-off on the runner; issue 23: an accuracy's answer does not depend on where or with what
else it was asked)."""

from __future__ import annotations

import pytest

from strokeopt.cli.main import main
from strokeopt.studies.runner import StudyRunner
from strokeopt.studies.tradeoff import tradeoff_optimal


@pytest.mark.slow  # the drive's own rate, then 0.1 mm as a task: twice, about a minute
def test_the_tradeoff_on_workers_gives_the_table_of_one_worker(reference):
    here = tradeoff_optimal(reference, [0.1e-3, 0.5e-3], resolution=50.0)
    there = tradeoff_optimal(reference, [0.1e-3, 0.5e-3], resolution=50.0, runner=StudyRunner(2))
    # the same solves wherever they run: the same rates and limits; the errors to 1e-4 (in a test process that ran
    # other solves first, whose NLP caches it shares, the error at the rejected rate came out 2e-6 relative apart
    # and at the confirmed rate 1e-8)
    for a, b in zip(here, there):
        a, b = a.as_dict(), b.as_dict()
        for key in ("handover_error_mm", "failed_error_mm"):
            x, y = a.pop(key), b.pop(key)
            assert (x is None and y is None) or x == pytest.approx(y, rel=1e-4)
        a.pop("detail"), b.pop("detail")  # its text prints the errors to four digits
        assert a == b
    tight, loose = here
    # 0.5 mm: the drive's own rate answers it (its error is within); 0.1 mm: its own task, confirmed below it
    assert loose.binding == "torque_limit" and loose.handover_error <= 0.5e-3
    assert tight.max_spm <= loose.max_spm and tight.handover_error <= 0.1e-3 * (1 + reference.design.check_tolerance)


def test_an_unreachable_scheduler_is_refused_before_the_classic_law_runs(capsys, reference_path):
    assert main(["tradeoff", str(reference_path), "--scheduler", "tcp://127.0.0.1:1", "--plot", "none"]) == 2
    err = capsys.readouterr().err
    assert "--scheduler: cannot reach the Dask scheduler at tcp://127.0.0.1:1" in err
    assert "modified_sine" not in err  # no simulated rate of the classic law was printed first
