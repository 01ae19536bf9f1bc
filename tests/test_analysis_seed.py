"""The campaign's `seed` seeds every draw of the analysis (issue 43, 45 item 5): the PCE's band and PDF
draws and its exceedance draws differ between seeds 1 and 2 while the projection's mean, which draws
nothing, is the same; the same seed gives the same bits."""
import numpy as np

from uqflight.campaign.record import read_record
from uqflight.analysis.statistics import analyse
from uqflight.store import ResultStore

from conftest import run_python_campaign

TEXT = """
name: seeded-{seed}
seed: {seed}
simulator: {{kind: python, function: "uqflight.simulators.models:exp_decay"}}
parameters:
  a: {{distribution: normal, lower: 0.5, upper: 1.5}}
  b: {{distribution: uniform, lower: 1.0, upper: 2.0, nominal: 1.4}}
design: {{kind: sparse_grid, level: 3}}
method: {{kind: pseudo_galerkin, order: 2}}
analysis: {{band_samples: 500, bootstrap: 0, exceedance: {{final: [{{above: 0.01}}]}}}}
quantities:
  final: {{of: x, take: final}}
"""


def test_the_campaign_seed_reaches_the_band_and_exceedance_draws(tmp_path):
    files = {name: run_python_campaign(tmp_path, TEXT.format(seed=seed), name)
             for name, seed in (("one", 1), ("two", 2), ("again", 1))}
    with ResultStore.open(files["two"]) as store:
        assert read_record(store.attrs, "f").campaign.seed == 2
    one, two, again = (analyse(files[name]) for name in ("one", "two", "again"))
    assert (one.seed, two.seed) == (1, 2)
    x1, x2, x1_again = (stats.outputs["x"] for stats in (one, two, again))
    # the grid does not depend on the seed, so the projection's mean (a weighted sum) is the same bits
    np.testing.assert_array_equal(x1.mean, x2.mean)
    # 500 band draws of a spread output: two seeds' 0.5 % quantiles differ at every time but t = 0,
    # where every run starts at 1 and the spread is nil
    assert np.all(x1.band99[0][1:] != x2.band99[0][1:])
    assert not np.array_equal(x1.pdf_density, x2.pdf_density)
    q1, q2 = one.quantities["final"].exceedance[0], two.quantities["final"].exceedance[0]
    assert q1["probability"] != q2["probability"]
    # the same seed: the same bits
    np.testing.assert_array_equal(x1.band99[0], x1_again.band99[0])
    np.testing.assert_array_equal(x1.pdf_density, x1_again.pdf_density)
    assert q1 == again.quantities["final"].exceedance[0]
