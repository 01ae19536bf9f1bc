"""The report's page of each screening design's measures (`uqflight.analysis.statistics.Screening`): one module
per screening in this package, registered in SCREENINGS under the screening's name (the design kind's
`screening_name`) when the package is imported; the report's sections and headline look it up there."""
from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class ScreeningPage:
    """What the report shows of one screening's measures.

    Attributes
    ----------
    section : callable
        (entries, times, out_dir) -> Section: its section of the page.
    ranked_text : callable
        (measures, time index) -> str: the inputs ranked by importance, for the headline.
    column : str
        The headline's column of that ranking.
    sentence : str
        What the headline's text says of it.
    stage : str
        The progress line while its section is drawn.
    """

    section: Callable
    ranked_text: Callable
    column: str
    sentence: str
    stage: str


SCREENINGS: dict[str, ScreeningPage] = {}

for _module in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_module.name}")
