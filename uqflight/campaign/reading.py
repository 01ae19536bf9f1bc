"""Where a campaign's files are, and the campaign as a mapping to write elsewhere (calibrate's
`calibrated.yaml`); a results file's campaign is read by `campaign.record.read_record`."""
from __future__ import annotations

import copy
from pathlib import Path

from . import Campaign


def portable_mapping(campaign: Campaign) -> dict:
    """The campaign's mapping as written (a copy), with the files its simulator names relative to the
    campaign's folder (a model file, an aircraft folder, a script) made absolute: the same campaign when
    written elsewhere."""
    mapping = copy.deepcopy(campaign.mapping)
    mapping["simulator"] = campaign.simulator.entry.relocated(mapping["simulator"], campaign_folder(campaign))
    return mapping


def campaign_folder(campaign: Campaign) -> Path:
    """The folder of the campaign file (where its python model and relative paths are looked up)."""
    return Path(campaign.source).resolve().parent


def check_campaign_text(text: str, source: str) -> None:
    """Validate campaign text as `uqflight plan` does (CampaignError when it would be refused)."""
    from ..simulators.aircraft_properties import AircraftProperties
    from . import parse_campaign

    parse_campaign(text, source, read_aircraft=AircraftProperties)
