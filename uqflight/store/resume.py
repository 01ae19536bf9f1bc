"""Resume policy: reopen a campaign's results file when it holds the same campaign and aircraft,
create it otherwise, and compact a finished tSVD file."""
from __future__ import annotations

from pathlib import Path

import h5py

from .file_end import extend_file, past_recorded_end
from .lock import LockHeld, held_message, is_lock_error, open_elsewhere
from .results import READ_ERRORS, ResultStore, one_line, text_hash


FLOWN = ("aircraft_hash", "scenario")  # what a results file's runs flew beside the campaign text (the
# aircraft's files; a script scenario's script and initialisation files, simulators.simulator_provenance)


def open_for_campaign(path, *, campaign_text: str, force: bool = False, restart: bool = False,
                      **create_args) -> ResultStore:
    """Resume `path` when it holds this campaign, else create it (see ResultStore.create).

    A file holding another campaign (a different campaign_hash), or made with other aircraft or script
    files (attrs["aircraft_hash"], attrs["scenario"]), is refused unless `force`, which deletes and recreates it. `force`
    never deletes what is not a uqflight results file (a directory, a text file, another HDF5 file):
    those are refused, with how to remove them. (The caller holds the file's lock: `force` never
    touches a file another run writes.) `restart` starts a results file of this same campaign over.
    A file another process holds open (HDF5's file lock: a reader, or a writer without our lock) is
    refused with LockHeld naming that process, before anything is read: it is in use, not damaged,
    and neither `force` nor `restart` replaces it.
    """
    path = Path(path)
    flown = {key: (create_args.get("attrs") or {}).get(key) for key in FLOWN}
    if path.is_dir():
        raise FileExistsError(f"{path} is a directory, not a results file; choose a file path such as "
                              f"{path / 'results.h5'}")
    if path.exists() or path.is_symlink():
        if not path.is_file():
            raise FileExistsError(f"{path} is not a regular file; uqflight does not replace it: choose "
                                  "another results file")
        if not h5py.is_hdf5(path):
            raise FileExistsError(f"{path} is not a uqflight results file (not HDF5); uqflight never "
                                  f"overwrites it, even with --force: remove it yourself (rm {path}) or "
                                  "choose another results file")
        try:
            stored, stored_flown, ours = _stored_campaign(path)
        except READ_ERRORS as exc:  # e.g. killed while the file was being created: nothing to resume
            if is_lock_error(exc):  # opened by another process since the check above
                raise LockHeld(held_message(path)) from None
            if not force:
                reason = one_line(exc)[:200]
                if past_recorded_end(reason):  # and _stored_campaign could not move that end
                    reason += "; its data run past the end its superblock records, and that end could not be mended"
                raise FileExistsError(f"{path} is a damaged HDF5 file ({reason}); choose another results "
                                      "file, or force to overwrite it") from exc
            stored, stored_flown = None, {}
            ours = True
        if not ours:
            raise FileExistsError(f"{path} is an HDF5 file but not a uqflight results file (no campaign_hash "
                                  "or /samples/status); uqflight never overwrites it, even with --force: "
                                  f"remove it yourself (rm {path}) or choose another results file")
        if stored == text_hash(campaign_text) and stored_flown == flown and not restart:
            return ResultStore.open(path, "a")  # LockHeld when another process opened it since the check
        if restart and stored == text_hash(campaign_text):
            force = True
        if not force:
            if stored == text_hash(campaign_text):
                key = next(key for key in FLOWN if stored_flown.get(key) != flown[key])
                what = {"aircraft_hash": "aircraft files (sha256", "scenario": "script files ("}[key]
                raise FileExistsError(f"{path} was made with other {what} {str(stored_flown.get(key))[:80]}); "
                                      "resuming would mix two models: choose another results file, or force "
                                      "to start over")
            raise FileExistsError(f"{path} holds the results of another campaign (campaign_hash {stored}); "
                                  "choose another results file, or force to overwrite it")
        if open_elsewhere(path):  # opened meanwhile: it is in use, and stays
            raise LockHeld(held_message(path))
        path.unlink()
    try:
        return ResultStore.create(path, campaign_text=campaign_text, **create_args)
    except BaseException:  # e.g. a full disk: a half-made file would later look damaged; nothing is lost
        if path.exists():
            path.unlink()
        raise


def _stored_campaign(path: Path) -> tuple:
    """The file's campaign_hash, its FLOWN attributes, and whether it is a uqflight results file. A read
    past the file's recorded end (a writer killed inside HDF5's flush, file_end) moves that end to the
    file's and reads again: such a file resumes like any other."""
    def read() -> tuple:
        with h5py.File(path, "r") as f:
            stored = f.attrs.get("campaign_hash")
            return stored, {key: f.attrs.get(key) for key in FLOWN}, stored is not None and "samples/status" in f

    try:
        return read()
    except READ_ERRORS as exc:
        if not (past_recorded_end(str(exc)) and extend_file(path)):
            raise
    return read()


def compact(path) -> None:
    """Rewrite a file without the free space its replaced tSVD factors left behind (HDF5 does not
    reclaim it: a 10^4-run file shrinks about tenfold). Written to a temporary file, then renamed
    over the original, so a kill leaves one complete file."""
    path = Path(path)
    scratch = path.with_name(path.name + ".compacting")
    with h5py.File(path, "r") as src, h5py.File(scratch, "w") as dst:
        dst.attrs.update(dict(src.attrs))
        for key in src:
            src.copy(src[key], dst, name=key)
    scratch.replace(path)
