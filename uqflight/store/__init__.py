"""The HDF5 results file: its layout (`results`), compressed tSVD storage (`compressed`) and the resume
policy (`resume`)."""
from ..simulators.base import Status
from .resume import compact, open_for_campaign
from .results import ResultStore, text_hash

__all__ = ["ResultStore", "Status", "compact", "open_for_campaign", "text_hash"]
