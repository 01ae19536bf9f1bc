"""Wrapped angles, pick-freeze indices that say how sure they are, indices that survive failed runs, and
units (issue 45 items 2, 3, 4, 7), on closed-form models; each tolerance is stated with its reason."""
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import run_python_campaign

from uqflight.analysis.statistics import analyse, summary_json

MODELS = Path(__file__).parent / "data" / "sensitivity_models.py"
PI = math.pi
ISHIGAMI_BOX = "".join(f"  x{i}: {{distribution: uniform, lower: {-PI}, upper: {PI}}}\n" for i in (1, 2, 3))
S1 = np.array([0.3139, 0.4424, 0.0])  # Ishigami's closed-form indices (a = 7, b = 0.1)
ST = np.array([0.5576, 0.4424, 0.2437])


def campaign(name: str, function: str, parameters: str, design: str, extra: str = "", analysis: str = "",
             model: Path = MODELS) -> str:
    return (f"name: {name}\nseed: 7\nsimulator: {{kind: python, function: \"{model}:{function}\"}}\n"
            f"parameters:\n{parameters}design: {design}\nmethod: {{kind: monte_carlo}}\n{extra}"
            f"analysis: {{band_samples: 2000, bootstrap: 200{analysis}}}\n")


TURN = campaign("turn", "wrapped_turn", "  a: {distribution: uniform, lower: 1, upper: 3}\n"
                "  b: {distribution: uniform, lower: -2, upper: 2}\n", "{kind: monte_carlo, samples: 400}",
                "quantities:\n  final_heading: {of: psi_deg, take: final}\n"
                "  heading_change: {of: psi_deg, take: change}\n"
                "  bank: {of: psi_deg, take: max}\n")
UNIT_BOX = "".join(f"  x{i}: {{distribution: uniform, lower: 0, upper: 1}}\n" for i in (1, 2, 3))
SMOOTH = campaign("linear-pf", "linear", UNIT_BOX, "{kind: pick_freeze, samples: 256}",
                  "quantities:\n  y_final: {of: y, take: final}\n"
                  "  y_time: {take: time_of_first, when: {of: y, above: -100}}\n",
                  ", exceedance: {y_final: [{above: 4}, {above: 90}]}",
                  model=Path(__file__).parent.parent / "uqflight" / "simulators" / "models.py")


@pytest.fixture(scope="module")
def turn(flown):
    return analyse(flown(TURN, "turn"))


def test_a_heading_crossing_180_is_unwrapped_before_its_statistics(turn):
    # psi = 179 + b + a t wrapped to [-180, 180): unwrapped, mean 179 + 2t (on the first run's branch, so
    # modulo 360) and std sqrt(t²/3 + 4/3). 400 Monte Carlo runs: 4 standard errors of the mean (σ/√400 <=
    # 0.3 deg) and 15 % on the std (its relative standard error is about 1/√(2·400) = 3.5 %).
    out = turn.outputs["psi_deg"]
    t = out.time
    assert out.units == "deg" and out.unwrapped
    offset = (out.mean - (179 + 2 * t) + 180) % 360 - 180
    assert np.all(np.abs(offset) < 4 * np.sqrt(t**2 / 3 + 4 / 3) / 20)
    np.testing.assert_allclose(out.std, np.sqrt(t**2 / 3 + 4 / 3), rtol=0.15)
    assert np.ptp(out.band99[1] - out.band99[0]) < 40  # wrapped, the band would span the whole turn
    assert any(note.startswith("output psi_deg is an angle whose runs jump by about a turn") for note in turn.notes)


def test_a_heading_quantity_and_a_heading_change_are_continuous(turn):
    # final = 179 + b + 10 a (mean 199 mod 360, std sqrt(100/3 + 4/3)); change = 10 a: mean 20, std 10/√3,
    # whichever runs cross ±180; tolerances as above
    final, change = (turn.quantities[name] for name in ("final_heading", "heading_change"))
    assert final.units == change.units == "deg"
    assert abs((final.output.mean[0] - 199 + 180) % 360 - 180) < 4 * 6.0 / 20
    assert final.output.std[0] == pytest.approx(np.sqrt(104 / 3), rel=0.15)
    assert change.output.mean[0] == pytest.approx(20, abs=4 * 5.8 / 20)
    assert change.output.std[0] == pytest.approx(10 / np.sqrt(3), rel=0.15)
    entry = summary_json(turn)["quantities"]["heading_change"]
    assert entry["units"] == "deg" and entry["flags"] == []


def test_an_angle_that_does_not_wrap_is_left_to_the_bit():
    from uqflight.analysis.angles import branch_shifts, unwrapped_runs

    runs = np.array([[10.0, 50.0, 170.0], [-20.0, 60.0, 179.0], [5.0, -90.0, -170.0]])
    found, moved = unwrapped_runs(runs, 360.0)
    assert not moved and found is runs
    assert not branch_shifts(np.array([-170.0, 0.0, 170.0]), 360.0).any()  # spread over the turn: kept
    np.testing.assert_array_equal(branch_shifts(np.array([179.0, -179.0, 178.0]), 360.0), [0.0, 360.0, 0.0])


def test_units_come_from_jsbsim_property_names():
    from uqflight.quantities import QuantitySpec, When
    from uqflight.text.labels import name_unit

    assert [name_unit(n) for n in ("attitude/psi-deg", "velocities/vc-kts", "velocities/u-fps", "aero/qbar-psf",
                                    "position/h-sl-mt", "simulation/sim-time-sec", "inertia/weight-lbs",
                                    "fcs/aileron-pos-norm", "velocities/p-rad_sec", "accelerations/Nz", "y")] == [
        "deg", "kt", "ft/s", "psf", "m", "s", "lbs", "-", "rad/s", "g", ""]
    assert QuantitySpec("q", "drop", of="h_ft").unit({}) == "ft"
    assert QuantitySpec("q", "change", of="attitude/psi-deg").unit({}) == "deg"
    assert QuantitySpec("q", "time_of_first", when=When("h_ft", "above", 1.0)).unit({}) == "s"
    assert QuantitySpec("q", "short_period_damping").unit({}) == "-"
    assert QuantitySpec("q", "short_period_frequency_rad_s").unit({}) == "rad/s"
    assert QuantitySpec("q", "max", of="y").unit({"y": "N"}) == "N"


def test_pick_freeze_with_n_32_says_its_indices_are_unresolved(flown):
    from uqflight.report.sensitivity import top_contributors

    stats = analyse(flown(campaign("ishigami-32", "ishigami_failing", ISHIGAMI_BOX,
                                   "{kind: pick_freeze, samples: 32}"), "ishigami-32"))
    out = stats.outputs["y"]
    assert out.flags and "unresolved" in out.flags[0] and "n too small" in out.flags[0]
    assert any(note.startswith("output y: Sobol' indices of") for note in stats.notes)
    text = top_contributors(out.sobol_first, 0, out.sobol_first_ci)
    assert "n too small" in text and "interactions" not in text
    shares = [int(part.split(" %")[0].split()[-1]) for part in text.split(", ") if " % " in part]
    assert all(0 <= share <= 100 for share in shares)


def test_an_exceedance_from_runs_is_not_flagged_for_the_indices_of_the_same_runs(flown):
    # 32 base rows resolve no Sobol' index, which flags the quantity; the proportion of runs above 5 and its
    # Wilson interval do not rest on them: its entry carries no such flag (the headline marked it with them)
    stats = analyse(flown(campaign("ishigami-32-peak", "ishigami_failing", ISHIGAMI_BOX,
                                   "{kind: pick_freeze, samples: 32}", "quantities:\n  peak: {of: y, take: max}\n",
                                   ", exceedance: {peak: [{above: 5}]}"), "ishigami-32-peak"))
    quantity = stats.quantities["peak"]
    assert quantity.flags and "unresolved" in quantity.flags[0]
    entry, = quantity.exceedance
    assert entry["method"] == "wilson" and not any("Sobol'" in flag for flag in entry["flags"])
    assert summary_json(stats)["quantities"]["peak"]["exceedance"][0]["flags"] == entry["flags"]


def test_headline_shares_carry_their_intervals_and_never_exceed_100_percent():
    from uqflight.report.sensitivity import top_contributors

    first = {"a": np.array([0.62]), "b": np.array([1.02]), "c": np.array([9.34])}
    ci = {"a": np.array([[0.55], [0.70]]), "b": np.array([[0.97], [1.08]]), "c": np.array([[-2.0], [20.0]])}
    assert top_contributors(first, 0, ci) == ("b 100 % (97–100 %), a 62 % (55–70 %), "
                                              "c unresolved (-2 to 20, n too small)")
    assert top_contributors(first, 0) == "c 100 %, b 100 %, a 62 %"  # no share beyond 100 %, intervals or not


def test_sobol_indices_survive_a_few_failed_runs(flown):
    # Ishigami failing on 4 % of its points (scattered: a hash of the point), 256 base rows: the indices of
    # the complete rows hold the exact ones within their 95 % bootstrap intervals (checked for all six)
    stats = analyse(flown(campaign("ishigami-fail", "ishigami_failing", ISHIGAMI_BOX,
                                   "{kind: pick_freeze, samples: 256}"), "ishigami-fail"))
    assert 0.02 < stats.failed / stats.runs < 0.06
    out = stats.outputs["y"]
    for k, p in enumerate(("x1", "x2", "x3")):
        assert out.sobol_first_ci[p][0, 0] <= S1[k] <= out.sobol_first_ci[p][1, 0], p
        assert out.sobol_total_ci[p][0, 0] <= ST[k] <= out.sobol_total_ci[p][1, 0], p
    dropped = [note for note in stats.notes if "complete base rows" in note]
    assert len(dropped) == 1 and "rows dropped" in dropped[0]
    assert out.flags == []


def test_a_smooth_model_is_not_flagged_and_a_unit_slip_is(flown):
    # y = x1 + 2 x2 + 3 x3 on U(0, 1)³: S_i = (1, 4, 9)/14 exactly, and pick-freeze of a linear model is
    # precise (the intervals of 256 rows are ~0.05 wide): nothing flagged. The runs span [0, 6]: a threshold
    # of 90 lies 14 widths beyond them (a unit slip), 4 within
    stats = analyse(flown(SMOOTH, "linear-pf"))
    out = stats.outputs["y"]
    for k, p in enumerate(("x1", "x2", "x3")):
        assert out.sobol_first[p][0] == pytest.approx((1, 4, 9)[k] / 14, abs=0.05)
    assert out.flags == [] and out.units == ""
    quantity = stats.quantities["y_final"]
    assert quantity.output.flags == [] and len(quantity.flags) == 1 and "unit slip" in quantity.flags[0]
    assert stats.quantities["y_time"].flags == []
    near, far = quantity.exceedance
    assert "unit slip" in far["note"] and "run more" not in far["note"] and "unit slip" not in near["note"]
    assert near["flags"] == [] and far["flags"] == quantity.flags  # each threshold's own flag alone
    assert far["probability"] == 0.0
    summary = summary_json(stats)
    assert summary["outputs"]["y"]["flags"] == [] and summary["quantities"]["y_time"]["units"] == "s"
    assert summary["quantities"]["y_final"]["flags"] == quantity.flags
    assert any("unit slip" in note for note in summary["notes"])


@pytest.mark.slow  # 9 JSBSim flights of 100 s (about 10 s): the wrapped models above are the fast check
def test_the_737_turn_heading_is_continuous(tmp_path):
    # JSBSim's 737_cruise_steady_turn starts at heading 0 and drifts below it before turning right:
    # attitude/psi-deg jumps from 0 to 359.9 in every run. Unwrapped, the heading rises to about 136 deg at
    # 100 s with a spread of tenths of a degree; wrapped, its std would be ~180 deg
    text = (Path(__file__).parent.parent / "campaigns" / "737-turn.yaml").read_text()
    text = (text.replace("level: 2}", "level: 1}").replace("order: 2}", "order: 1}")
            .replace("workers: 2", "workers: 1")
            .replace("quantities:\n", "quantities:\n  heading_change: {of: attitude/psi-deg, take: change}\n"))
    stats = analyse(run_python_campaign(tmp_path, text, "turn737"))
    psi = stats.outputs["attitude/psi-deg"]
    assert psi.units == "deg" and psi.unwrapped and np.max(psi.std) < 1.0
    assert 100 < psi.mean[-1] < 170 and np.all(np.diff(psi.mean[200:]) > 0)
    change = stats.quantities["heading_change"]
    assert change.units == "deg" and change.output.std[0] < 1.0
    assert change.output.mean[0] == pytest.approx(psi.mean[-1] - psi.mean[0], abs=0.5)
    assert stats.quantities["altitude_loss_ft"].units == "ft" and stats.quantities["peak_load_factor"].units == "g"


@pytest.mark.slow
def test_a_wrapped_heading_stored_as_tsvd_factors_is_unwrapped_as_the_raw_one(flown, turn):
    # the same 400 runs stored as tSVD factors (tol 1e-12: the wrapped histories rebuilt to ~1e-9 deg):
    # unwrapped from the rebuilt runs, the statistics equal the raw file's to 1e-6 deg
    text = TURN.replace("name: turn", "name: turn-tsvd") + "storage: {raw: false, tsvd: {tol: 1.0e-12}}\n"
    stats = analyse(flown(text, "turn-tsvd"))
    out, raw = stats.outputs["psi_deg"], turn.outputs["psi_deg"]
    assert out.unwrapped
    np.testing.assert_allclose(out.mean, raw.mean, atol=1e-6)
    np.testing.assert_allclose(out.std, raw.std, atol=1e-6)


def test_an_index_is_unresolved_by_its_interval_only():
    from uqflight.analysis.sobol import unresolved

    index = np.array([0.5, 0.5, 1.3, -0.2, 1.02, -0.01, np.nan])
    lower = np.array([0.1, 0.2, 1.1, -0.3, 0.97, -0.01, np.nan])
    upper = np.array([0.7, 0.6, 1.5, -0.1, 1.08, -0.01, np.nan])  # widths 0.6 0.4 0.4 0.2 0.11 0 -
    assert unresolved(index, (lower, upper)).tolist() == [True, False, True, True, False, False, False]


def test_the_variance_split_survives_failed_runs(flown):
    # a seed parameter (a turbulence realisation) and x, failing on about 4 % of the runs: the split of the
    # complete rows holds the exact shares (seed 0.2, the others 0.8) within its 95 % intervals
    text = (f"name: split\nseed: 3\nsimulator: {{kind: python, function: \"{MODELS}:turbulent_failing\"}}\n"
            "parameters:\n  x: {distribution: normal, lower: -3, upper: 3}\n"
            "  seed: {distribution: seed}\ndesign: {kind: pick_freeze, samples: 256}\n"
            "analysis: {band_samples: 2000, bootstrap: 200}\n")
    stats = analyse(flown(text, "split"))
    assert stats.failed > 0
    split = summary_json(stats)["outputs"]["y"]["variance_split"]
    for group, share in (("seeds", 0.2), ("other_parameters", 0.8)):
        for order in ("first", "total"):
            interval = split[group][f"{order}_ci"]
            assert interval["lower"][0] <= share <= interval["upper"][0], (group, order)
    assert any("rows dropped" in note for note in stats.notes)


def test_the_unresolved_flag_counts_the_times_of_non_negligible_variance_only():
    from types import SimpleNamespace

    from uqflight.analysis.statistics import unresolved_flag

    wide, narrow = np.array([[0.0, 0.0, 0.1], [1.0, 1.0, 0.2]]), np.array([[0.0, 0.4, 0.1], [0.1, 0.5, 0.2]])
    # t = 0: variance 1e-6 of the largest (negligible), its wide interval not counted; t = 1: wide, counted
    out = SimpleNamespace(time=np.arange(3.0), variance=np.array([1e-6, 1.0, 1.0]),
                          sobol_first={"a": np.array([0.5, 0.5, 0.15]), "b": np.array([0.05, 0.45, 0.15])},
                          sobol_total={"a": np.array([0.5, 0.5, 0.15]), "b": np.array([0.05, 0.45, 0.15])},
                          sobol_first_ci={"a": wide, "b": narrow}, sobol_total_ci={"a": wide, "b": narrow})
    flag = unresolved_flag(out)
    assert flag.startswith("Sobol' indices of a unresolved at 1 of 2 times of non-negligible variance (n too small)")
    out.sobol_first_ci = out.sobol_total_ci = {"a": narrow, "b": narrow}
    assert unresolved_flag(out) is None
