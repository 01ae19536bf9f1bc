"""Campaign limits: designs, memory, disk, PCE terms and campaign files too large are refused before
anything is built or run, naming the limit and how to raise it; names that are not safe are refused."""
import pytest
from conftest import cli_in_process, hostile_campaign

from uqflight.campaign import parse_campaign
from uqflight.running.runner import run_campaign


BASE = """
name: {name}
simulator: {{kind: jsbsim, duration_s: {duration}}}
parameters:
  CL0: {{property: aero/uq/CL0, distribution: normal, lower: 0.2, upper: 0.3}}
  k2:  {{property: aero/uq/k2, distribution: normal, lower: 0.01, upper: 0.05}}
  V:   {{property: ic/vt-kts, distribution: normal, lower: 195, upper: 205}}
design: {design}
method: {method}
"""


def refused(text, match, source="limits.yaml"):
    import tracemalloc

    from uqflight.campaign import CampaignError

    tracemalloc.start()
    try:
        with pytest.raises(CampaignError, match=match) as info:
            parse_campaign(text, source)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 50e6, f"{peak / 1e6:.0f} MB allocated before refusing"
    assert len(str(info.value)) < 2500
    return str(info.value)


def limited(name="lim", duration=5, design="{kind: monte_carlo, samples: 10}",
            method="{kind: monte_carlo, order: 2}"):
    return BASE.format(name=name, duration=duration, design=design, method=method)


@pytest.mark.parametrize("design", ["{kind: monte_carlo, samples: 1000000000000}",
                                    "{kind: sobol, samples: 1000000000}",
                                    "{kind: sobol, samples: 1000, replicates: 2000}",
                                    "{kind: pick_freeze, samples: 400000000}"])
def test_too_many_samples_are_refused_up_front(design):
    refused(limited(design=design), r"design: .* runs \(points built\), more than limits.max_runs = 1000000")


@pytest.mark.parametrize("design", ["{kind: sparse_grid, rule: gauss_hermite, level: 50}",
                                    "{kind: tensor_grid, rule: gauss_hermite, points: 1000}"])
def test_too_large_grids_are_refused_up_front(design):
    refused(limited(design=design, method="{kind: integration, order: 2}"), r"limits.max_runs")


def test_a_huge_level_is_refused_up_front():
    refused(limited(design="{kind: sparse_grid, rule: gauss_hermite, level: 1000000000}",
                    method="{kind: integration, order: 2}"), r"design.level: expected at most 1000")


def test_a_raised_limit_lets_a_large_design_through():
    text = limited(design="{kind: monte_carlo, samples: 2000000}") + "limits: {max_runs: 3000000}\n"
    from uqflight.campaign.schema import CampaignLoader, Checker
    from uqflight.campaign.sections import Limits
    import yaml
    data = yaml.load(text, Loader=CampaignLoader)
    found = Limits.checked(Checker("x"), data["limits"])
    assert found.max_runs == 3000000 and found.max_memory_gb == Limits.max_memory_gb


def test_a_long_flight_is_refused_by_its_memory_or_disk():
    refused(limited(duration="1e9"), r"more than limits.max_(memory|disk)_gb")


def test_more_worker_processes_than_memory_allows_are_refused():
    """A local worker process takes ~52 MB (measured; counted as 60): 1000 of them pass 8 GB."""
    refused(limited() + "execution: {workers: 1000}\n",
            r"design: .* GB of memory .*1000 worker processes of 60 MB\), more than limits.max_memory_gb = 8")
    refused(limited() + "execution: {workers: 1000, executor: dask}\n", r"1000 worker processes")  # a LocalCluster
    parse_campaign(limited() + "execution: {workers: 1000, executor: dask, scheduler: 'tcp://10.0.0.1:8786'}\n",
                   "cluster.yaml")  # another machine's processes


def test_workers_asked_on_the_command_line_are_refused_beyond_memory_and_capped_at_the_chunks(tmp_path):
    from uqflight.running.runner import local_workers

    spec = hostile_campaign("slow", samples=15, chunk=16)  # chunks of 4 at the design's end: 0, 4, 8, 12
    assert spec.runs == 15 and local_workers(spec, 50, 16) == 4 and local_workers(spec, 3, 16) == 3
    with pytest.raises(ValueError, match=r"100000 workers would need about 6e\+03 GB of memory \(60 MB each\), "
                                         r"more than limits.max_memory_gb = 8"):
        run_campaign(spec, out=tmp_path / "r.h5", workers=100000)
    assert not (tmp_path / "r.h5").exists()


def test_a_huge_pce_order_is_refused():
    refused(limited(design="{kind: sparse_grid, rule: gauss_hermite, level: 2}",
                    method="{kind: integration, order: 1000}"), r"method.order: .* more than limits.max_pce_terms")


def test_yaml_aliases_are_refused():
    bomb = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{chr(98 + i)}: &{chr(98 + i)} [*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, "
        f"*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}]\n" for i in range(8))
    text = limited().replace("design: {kind: monte_carlo, samples: 10}",
                             "design: {kind: monte_carlo, samples: 10, extra: *i}") + bomb
    refused(text, "YAML aliases")


def test_a_huge_campaign_file_is_refused(tmp_path):
    from uqflight.campaign import CampaignError, load_campaign

    path = tmp_path / "big.yaml"
    path.write_text(limited() + "description: " + "x" * (2 << 20) + "\n")
    with pytest.raises(CampaignError, match="larger than 1024 KiB"):
        load_campaign(path)


@pytest.mark.parametrize("name", ["../../x", "a/b", ".hidden", "x" * 101, "spaces here"])
def test_unsafe_names_are_refused(name):
    refused(limited(name=f'"{name}"'), r"name: expected 1-100 characters")


def test_refusals_through_the_cli_exit_2(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text(limited(design="{kind: monte_carlo, samples: 1000000000000}"))
    for command in ("plan", "run"):
        done = cli_in_process(command, path)
        assert done.returncode == 2 and "limits.max_runs" in done.stderr, done.stderr


def test_a_campaign_whose_results_no_reader_holds_is_refused_up_front():
    """D08's other side: 10^6 runs of 5 s at 60 Hz (3.0e8 values per output) pass the memory and disk
    limits raised for it, but give a file every reader refuses (store.layout.MAX_OUTPUT_VALUES): refused at
    planning, not after the flights."""
    text = limited(design="{kind: monte_carlo, samples: 1000000}") + \
        "limits: {max_memory_gb: 1000, max_disk_gb: 10000}\n"
    refused(text.replace("duration_s: 5}", "duration_s: 5, output_rate_hz: 60}"),
            r"design: 1e\+06 runs x 301 times = 3.01e\+08 values per output, more than the results file's readers hold")
