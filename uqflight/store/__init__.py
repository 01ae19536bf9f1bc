"""The HDF5 results file: its layout (`results`), the outputs' storage forms behind one interface
(`storage`: raw histories in `raw`, tSVD factors in `compressed`) and the resume policy (`resume`)."""
from ..simulators.base import Status
from .resume import compact, open_for_campaign
from .lock import LockHeld, ResultsLock
from .results import CorruptFile, ResultStore, read_error, text_hash

__all__ = ["CorruptFile", "LockHeld", "ResultStore", "ResultsLock", "Status", "compact", "open_for_campaign",
           "read_error", "text_hash"]
