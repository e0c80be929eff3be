"""Population design: several random starts per design, the best continues to the polish."""

import numpy as np
import pytest

from jaxlens.design import multistart
from jaxlens.design.curriculum import History
from jaxlens.design.spec import DesignSpec

SMALL = DesignSpec(n_elements=2, materials=("E48R", "OKP4"), fov=40.0, fnum=4.0,
                   fov_start=30.0, fnum_start=4.0, total_track=3.0, bfl=0.8, asphere_terms=3)
TINY = dict(n_fields=3, rings=2, curriculum_n=1, steps=4, final_steps=4, epoch=4, log_every=4,
            float64=True)


def test_population_starts_are_disjoint_and_one_start_is_the_seed():
    assert multistart.population_starts([3, 7], 1) == [3, 7]
    starts = multistart.population_starts([0, 1, 5], 3)
    assert starts == [0, 1, 2, 3, 4, 5, 15, 16, 17]
    assert len(set(starts)) == len(starts)


def _history(rms, labels, failed=()):
    h = History()
    h.stages.append("fine-tune")
    h.spot_rms.append(np.asarray([rms], float))
    h.loss.append(np.asarray([rms], float))
    h.results.append(["successful"] * len(rms))
    h.seconds.append(0.0)
    h.failed.update({labels[i]: "non-finite" for i in failed})
    return h


def test_best_start_is_the_lowest_rms_and_never_a_failed_one():
    labels = [0, 1, 2, 3, 4, 5]
    h = _history([0.3, 0.1, 0.2, np.nan, 0.5, 0.05], labels, failed=[5])
    # Design 0: starts 0-2, best is 1; design 1: 3 is NaN and 5 failed, so 4.
    assert multistart.best_starts(h, labels, 2, 3) == [1, 4]
    # Every start of a design failed: its first start stays (and stays failed).
    h = _history([0.3, 0.1], [0, 1], failed=[0, 1])
    assert multistart.best_starts(h, [0, 1], 1, 2) == [0]


def test_history_select_keeps_columns_and_relabels_failures():
    h = _history([0.3, 0.1, 0.2], [10, 11, 12], failed=[0, 2])
    s = h.select([2, 1], relabel={12: 4, 11: 5})
    np.testing.assert_array_equal(s.spot_rms[0], [[0.2, 0.1]])
    assert s.failed == {4: "non-finite"}  # start 10 was not chosen, so its failure goes


@pytest.mark.slow  # 21 s (CI time; the polish test below runs the same four starts)
def test_population_design_continues_the_best_start():
    """Two starts per design: each design carries on from its start with the lower RMS
    after fine-tuning, the same as designing that start alone."""
    cfg1 = multistart.DesignConfig(**TINY, polish_steps=0)
    alone = multistart.design(SMALL, [0, 1, 2, 3], cfg1, progress=False, shard=False)
    rms = alone.history.spot_rms[-1][-1]
    cfg2 = multistart.DesignConfig(**TINY, polish_steps=0, population=2)
    # Designs 0 and 1 draw starts 0, 1 and 2, 3: the same four starts, so the same shapes
    # and compiled stages as ``alone`` (and as the polish test below).
    pop = multistart.design(SMALL, [0, 1], cfg2, progress=False, shard=False)
    best = [int(np.argmin(rms[:2])), 2 + int(np.argmin(rms[2:]))]
    assert pop.starts == best
    for i, b in enumerate(best):
        np.testing.assert_allclose(pop.params.c[i], alone.params.c[b], rtol=1e-9, atol=1e-12)
    assert pop.history.spot_rms[-1].shape[1] == 2


@pytest.mark.slow  # 23 s (CI time); CI keeps population_starts, best_starts and History.select
def test_population_design_polishes_only_the_survivors():
    # Four starts (two per design) run the curriculum, as in the test above, so its compiled
    # stages are reused; only the two survivors are polished.
    cfg = multistart.DesignConfig(**TINY, polish_steps=1, population=2)
    res = multistart.design(SMALL, [0, 1], cfg, progress=False, shard=False)
    assert res.history.stages[-1].startswith("polish")
    assert [h.shape[1] for h in res.history.spot_rms] == [2] * len(res.history.stages)
    assert res.starts[0] in (0, 1) and res.starts[1] in (2, 3)
    assert set(res.status) <= {"successful", "rejected", "damping_limit"}


def test_population_must_be_positive():
    with pytest.raises(ValueError, match="population must be at least 1"):
        multistart.design(SMALL, [0], multistart.DesignConfig(**TINY, population=0),
                          progress=False)


@pytest.mark.parametrize("value", ["0", "65"])
def test_cli_refuses_a_bad_population_before_work(value, capsys):
    from jaxlens.experiments import classical

    assert classical.main(["--population", value, "--out", "/nonexistent/x"]) == 2
    err = capsys.readouterr().err
    assert "--population" in err and "starts per design" in err


@pytest.mark.slow  # a non-default option (about 30-40 s on 2 cores); CI time
def test_polish_rings_change_only_the_polish_sampling():
    """The polish may use a finer pupil: with as many rings as the other stages it is the
    same design; with more rings only the polish differs."""
    base = dict(TINY, polish_steps=2)
    plain = multistart.design(SMALL, [0], multistart.DesignConfig(**base), progress=False,
                              shard=False)
    same = multistart.design(SMALL, [0], multistart.DesignConfig(**base, polish_rings=2),
                             progress=False, shard=False)
    finer = multistart.design(SMALL, [0], multistart.DesignConfig(**base, polish_rings=4),
                              progress=False, shard=False)
    np.testing.assert_allclose(same.params.c, plain.params.c, rtol=1e-12, atol=1e-15)
    for a, b in zip(plain.history.spot_rms[:-1], finer.history.spot_rms[:-1], strict=True):
        np.testing.assert_array_equal(a, b)  # every stage before the polish is unchanged
    # The polish measures its first spot (same parameters) on the finer pupil.
    assert plain.history.spot_rms[-1][0, 0] != pytest.approx(finer.history.spot_rms[-1][0, 0],
                                                             rel=1e-6)
