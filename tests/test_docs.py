"""The documentation: the campaign-key reference covers every key the validator accepts, the Python
API's docstring examples run, and (slow) the site builds strictly and the examples of docs/python.md run."""
import doctest
import re
import shutil
import subprocess
import sys

import pytest

import uqflight
from conftest import ROOT
from uqflight.campaign import parse_campaign
from uqflight.campaign.keys import accepted_keys, missing_descriptions, reference_page

PYTHON = 'name: c\nsimulator: {kind: python, function: "uqflight.simulators.models:linear"}\n' \
         "parameters: {x: {distribution: uniform, lower: 0, upper: 1}}\ndesign: {kind: monte_carlo, samples: 4}\n"


def test_every_key_and_kind_has_a_description():
    assert missing_descriptions() == []


def test_the_committed_key_reference_is_the_generated_one():
    # the build regenerates it (docs/hooks.py); the committed copy is what a reader of the repository sees
    committed = (ROOT / "docs" / "reference" / "campaign-keys.md").read_text()
    assert committed == reference_page(), \
        "regenerate it: python -m uqflight.campaign.keys > docs/reference/campaign-keys.md"


def accepted_by_validator(text: str) -> tuple[str, ...]:
    """The keys the whole validator lists when it refuses the unknown key '?' in campaign text ('... unknown
    key; expected one of a, b' from the schema's Checker, '... accepted keys: a, b' from a design kind)."""
    with pytest.raises(ValueError) as refused:
        parse_campaign(text, str(ROOT / "c.yaml"))
    found = re.search(r"(?:expected one of|accepted keys:) ([^;]+)$", str(refused.value))
    assert found, f"the refusal lists no accepted keys: {refused.value}"
    return tuple(k.strip() for k in found.group(1).split(","))


@pytest.mark.parametrize("prefix, text", [
    ("", PYTHON + "'?': 1\n"),
    ("simulator", PYTHON.replace("models:linear\"", "models:linear\", '?': 1")),
    ("parameters.NAME", PYTHON.replace("upper: 1}", "upper: 1, '?': 1}")),
    ("design", PYTHON.replace("samples: 4}", "samples: 4, '?': 1}")),
    ("method", PYTHON + "method: {kind: monte_carlo, '?': 1}\n"),
    ("execution", PYTHON + "execution: {'?': 1}\n"),
    ("storage", PYTHON + "storage: {'?': 1}\n"),
    ("storage.tsvd", PYTHON + "storage: {tsvd: {'?': 1}}\n"),
    ("analysis", PYTHON + "analysis: {'?': 1}\n"),
    ("limits", PYTHON + "limits: {'?': 1}\n"),
    ("quantities.NAME", PYTHON + "quantities: {q: {of: y, take: max, '?': 1}}\n"),
    ("simulator.flight", PYTHON.replace('{kind: python, function: "uqflight.simulators.models:linear"}',
                                        "{kind: jsbsim, flight: {'?': 1}}").replace("{x: {", "{x: {property: ic/h-sl-ft, ")),
    ("simulator.excitation", PYTHON.replace('{kind: python, function: "uqflight.simulators.models:linear"}',
                                            "{kind: jsbsim, excitation: {'?': 1}}").replace("{x: {", "{x: {property: ic/h-sl-ft, ")),
    ("simulator.scenario", PYTHON.replace('{kind: python, function: "uqflight.simulators.models:linear"}',
                                          "{kind: jsbsim, scenario: {kind: script, '?': 1}}")),
])
def test_the_reference_lists_every_key_the_validator_accepts(prefix, text):
    # the validator's own list of accepted keys, asked by refusing an unknown one, against the reference's
    documented = {k.path for k in accepted_keys()}
    for key in accepted_by_validator(text):
        if prefix == "simulator" and key in ("kind",):
            continue
        path = f"{prefix}.{key}" if prefix else key
        assert path in documented, f"{path} is accepted by the validator but not in the key reference"
        assert f"`{path}`" in reference_page()


def test_the_api_docstring_examples_run():
    # load_campaign -> run -> analyse -> export/load the surrogate on exp(-a t), and one JSBSim flight; the
    # mean checked against its closed form in the example itself
    result = doctest.testmod(uqflight, optionflags=doctest.ELLIPSIS)
    assert result.attempted >= 15 and result.failed == 0


def test_the_api_functions_have_numpydoc_parameters_returns_and_raises():
    for name in uqflight.__all__:
        doc = getattr(uqflight, name).__doc__
        for section in ("Parameters", "Returns", "Raises"):
            assert f"\n    {section}\n    {'-' * len(section)}\n" in doc, (name, section)


def test_import_uqflight_imports_nothing_else():
    code = "import sys, uqflight; print(sorted(m for m in sys.modules if m.startswith('uqflight')))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert loaded.strip() == "['uqflight']"


@pytest.mark.slow
def test_the_site_builds_strictly(tmp_path):
    # mkdocs --strict: a broken link, anchor or nav entry, or a key without a description, fails the build
    shutil.copytree(ROOT / "docs", tmp_path / "docs")
    shutil.copy(ROOT / "mkdocs.yml", tmp_path / "mkdocs.yml")
    built = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                           cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert built.returncode == 0, built.stderr
    page = (tmp_path / "site" / "reference" / "campaign-keys" / "index.html").read_text()
    assert "design.kind" in page and "quantities.NAME.take" in page


@pytest.mark.slow
@pytest.mark.parametrize("page, block", [("docs/python.md", 0), ("docs/python.md", 1), ("README.md", 0)])
def test_the_python_examples_run(tmp_path, page, block):
    code = re.findall(r"```python\n(.*?)```", (ROOT / page).read_text(), re.S)[block]
    (tmp_path / "campaigns").mkdir()
    shutil.copy(ROOT / "campaigns" / "ci-small.yaml", tmp_path / "campaigns")
    (tmp_path / "example.py").write_text(code)
    ran = subprocess.run([sys.executable, "example.py"], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert ran.returncode == 0, ran.stderr


def test_every_page_the_code_cites_exists():
    cited = {(path.relative_to(ROOT), page) for path in sorted((ROOT / "uqflight").rglob("*.py"))
             for page in re.findall(r"\b(docs/[\w/.-]+\.md|[A-Z]+\.md)\b", path.read_text())}
    assert cited, "no page cited: the pattern is wrong"
    missing = [f"{source} cites {page}" for source, page in cited if not (ROOT / page).is_file()]
    assert not missing
