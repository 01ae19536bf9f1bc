"""The report's reading of the campaign text stored in a results file (report.loading.campaign_settings)."""
from uqflight.report.loading import campaign_settings


def test_unreadable_campaign_text_gives_no_settings():
    # a stored campaign is the file's to hold: a YAML error, a date that is no date, nesting too deep
    # for Python and a mapping that is not one all read as {} instead of failing the report
    for text in ("a: [1, 2", "a: 2001-13-45", "[" * 3000 + "]" * 3000, "- 1\n- 2", "a: !!python/object:os.system x"):
        assert campaign_settings(text) == {}


def test_settings_are_a_copy_of_the_text_read_once():
    text = "seed: 3\nparameters:\n  CL0: {distribution: normal}\n"
    first = campaign_settings(text)
    first["parameters"]["CL0"]["distribution"] = "changed"
    assert campaign_settings(text) == {"seed": 3, "parameters": {"CL0": {"distribution": "normal"}}}
