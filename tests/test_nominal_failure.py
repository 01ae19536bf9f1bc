"""A failing nominal sample (the one `run` flies first, in a real worker process) of a python model stops
the run with one message that names it, gives its values and says what to do; exit 2, no results file. A
JSBSim flight's outputs are known without it: its runs are flown and recorded, and the summary warns."""
import pytest
from conftest import DATA, cli_in_process

MODEL = DATA / "failure_models.py"


def run(tmp_path, outputs="", interval="lower: 1.0, upper: 2.0", command="run", function=f"{MODEL}:fails_at_centre"):
    (tmp_path / "c.yaml").write_text(
        f"name: nominal\nsimulator: {{kind: python, function: \"{function}\"{outputs}}}\n"
        f"parameters:\n  a: {{distribution: uniform, {interval}, nominal: 1.4}}\n"
        "design: {kind: monte_carlo, samples: 8}\n")
    if command == "plan":
        return cli_in_process("plan", tmp_path / "c.yaml")
    return cli_in_process("run", tmp_path / "c.yaml", "--out", tmp_path / "c.h5")


def test_a_failing_nominal_sample_is_named_with_its_values_and_what_to_do(tmp_path):
    done = run(tmp_path)
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    message = lines[0]
    # ξ = 0 is the law's centre, 1.5, not the campaign's `nominal: 1.4`: the message gives the value flown
    assert message.startswith(f"error: {tmp_path / 'c.yaml'}: the nominal sample failed (a = 1.5: the centre")
    assert "RuntimeError: centre node" in message
    assert "call simulator.function with them" in message and "move the parameters' intervals" in message
    assert not (tmp_path / "c.h5").exists()


@pytest.mark.slow
def test_plan_says_what_run_says_of_a_nominal_sample_that_fails_or_returns_no_outputs(tmp_path):
    # plan times a nominal run: a model failing there was a traceback with exit 1
    for function, said in ((f"{MODEL}:fails_at_centre", "the nominal sample failed (a = 1.5: the centre"),
                           ("os:getcwd", "TypeError: ")):
        planned, ran = run(tmp_path, command="plan", function=function), run(tmp_path, function=function)
        assert planned.returncode == ran.returncode == 2, planned.stderr
        assert planned.stderr.startswith(f"error: {tmp_path / 'c.yaml'}: ") and said in planned.stderr
        assert len(planned.stderr.strip().splitlines()) == 1 and "Traceback" not in planned.stderr


def test_a_campaign_error_found_at_the_nominal_is_not_called_a_failing_sample(tmp_path):
    # the function succeeds at the nominal (2.5) but lacks the output the campaign asks for
    done = run(tmp_path, ", outputs: [z]", "lower: 2.0, upper: 3.0")
    assert done.returncode == 2
    assert "simulator.outputs: the function returned no 'z'" in done.stderr
    assert "nominal sample failed" not in done.stderr


def test_a_jsbsim_campaign_whose_nominal_does_not_trim_flies_on_and_says_so(tmp_path):
    # bacm cannot trim in level flight at 90 KTAS (below its stall speed): every run fails, each with its
    # reason (the outputs are known without the nominal), and the summary warns that the centre failed
    (tmp_path / "c.yaml").write_text(
        "name: nominal\nsimulator: {kind: jsbsim, aircraft: bacm, flight: {airspeed_ktas: 90}, duration_s: 1}\n"
        "parameters:\n  CL0: {property: aero/uq/CL0, distribution: normal, interval_pct: 5}\n"
        "design: {kind: monte_carlo, samples: 4}\n")
    done = cli_in_process("run", tmp_path / "c.yaml", "--out", tmp_path / "c.h5")
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert "4 failed" in done.stdout and "warning: the nominal flight" in done.stdout, done.stdout
    assert "stall" in done.stdout and "uqflight simulate" in done.stdout
