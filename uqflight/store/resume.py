"""Resume policy: reopen a campaign's results file when it holds the same campaign and aircraft,
create it otherwise, and compact a finished tSVD file."""
from __future__ import annotations

import os
from pathlib import Path

import h5py
import yaml

from ..text.console import quoted_name
from .file_end import extend_file, past_recorded_end
from .lock import LockHeld, held_message, is_lock_error, open_elsewhere
from .results import READ_ERRORS, ResultStore, error_line, text_hash


# top-level campaign keys that change how the stored runs are read, never what they flew: a file whose campaign
# differs in these alone is resumed with the new text (the report reads its analysis from there)
READ_ONLY_KEYS = ("analysis", "description")
FLOWN = ("aircraft_hash", "scenario")  # what a results file's runs flew beside the campaign text (the
# aircraft's files; a script scenario's script and initialisation files, simulators.simulator_provenance)


def open_for_campaign(path, *, campaign_text: str, force: bool = False, restart: bool = False,
                      **create_args) -> ResultStore:
    """Resume `path` when it holds this campaign, else create it (see ResultStore.create).

    A file holding another campaign (a different campaign_hash), or made with other aircraft or script
    files (attrs["aircraft_hash"], attrs["scenario"]), is refused unless `force`, which deletes and recreates it;
    the refusal names the first key where the campaigns differ. A campaign that differs in READ_ONLY_KEYS
    alone (analysis:, description:) resumes the file, which then stores the new text. `force`
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
        if not os.access(path, os.R_OK | os.W_OK):  # a file this user cannot read says nothing of its contents
            raise FileExistsError(f"{path} cannot be {'read' if not os.access(path, os.R_OK) else 'written'} by "
                                  "this user (its permissions); uqflight does not replace it: choose another results "
                                  "file, or give this user access to it")
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
                reason = error_line(exc)[:200]
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
        differs = None
        if stored != text_hash(campaign_text) and stored_flown == flown and not restart:
            stored_text = _stored_text(path)
            differs = first_difference(stored_text, campaign_text)
            if differs is not None and _only_read_keys_differ(stored_text, campaign_text):
                store = ResultStore.open(path, "a")  # the runs stand: the new reading of them is stored
                given = create_args.get("attrs") or {}  # the new campaign's record (campaign.record)
                store._file.attrs.update({"campaign": campaign_text, "campaign_hash": text_hash(campaign_text),
                                          **{key: given[key] for key in ("record",) if key in given}})
                return store
        if stored == text_hash(campaign_text) and stored_flown == flown and not restart:
            return ResultStore.open(path, "a")  # LockHeld when another process opened it since the check
        if restart and stored == text_hash(campaign_text):
            force = True
        if not force:
            if stored == text_hash(campaign_text):
                key = next(key for key in FLOWN if stored_flown.get(key) != flown[key])
                what = {"aircraft_hash": "aircraft files (sha256", "scenario": "script files ("}[key]
                raise FileExistsError(f"{path} was made with other {what} {quoted_name(str(stored_flown.get(key))[:80])}); "
                                      "resuming would mix two models: choose another results file, or force "
                                      "to start over")
            where = (f": its campaign differs first at {quoted_name(differs)}" if differs else
                     f" (campaign_hash {quoted_name(str(stored))})")
            if differs and differs.startswith("quantities"):
                where += (" (a quantity is computed in the worker at every integration step, finer than the "
                          "stored histories: a changed one is flown again)")
            raise FileExistsError(f"{path} holds the results of another campaign{where}; choose another results "
                                  "file (--out), or --force (force=True in Python) to overwrite it and fly every "
                                  "run again (a change of analysis: alone resumes the file as it is; "
                                  "`uqflight report --exceedance` changes thresholds without a run)")
        if open_elsewhere(path):  # opened meanwhile: it is in use, and stays
            raise LockHeld(held_message(path))
        path.unlink()
    try:
        return ResultStore.create(path, campaign_text=campaign_text, **create_args)
    except BaseException:  # e.g. a full disk: a half-made file would later look damaged; nothing is lost
        if path.exists():
            path.unlink()
        raise


def _stored_text(path: Path) -> str:
    """The campaign text a results file stores ("" when it has none)."""
    with h5py.File(path, "r") as f:
        text = f.attrs.get("campaign", "")
    return text.decode("utf-8", "replace") if isinstance(text, bytes) else str(text)


SAFE_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml's, ten times faster, where PyYAML has it


def campaign_mapping(campaign_text: str) -> dict:
    """A campaign text's mapping as written (YAML), {} when unreadable or not a mapping."""
    try:
        data = yaml.load(campaign_text, Loader=SAFE_LOADER)
    except (yaml.YAMLError, ValueError, RecursionError):  # e.g. a date 2001-13-45, or nesting too deep
        return {}
    return data if isinstance(data, dict) else {}


def first_difference(stored_text: str, campaign_text: str) -> str | None:
    """The first key (a dotted path such as analysis.exceedance.peak_nz[0].above, in the new campaign's
    order) where two campaign texts' mappings differ; None when they hold the same mapping (a comment or
    the layout differs) or when the stored text cannot be read."""
    stored, ours = campaign_mapping(stored_text), campaign_mapping(campaign_text)
    if not stored:
        return None
    return _difference(stored, ours, "")


def _difference(old, new, path: str) -> str | None:
    if isinstance(old, dict) and isinstance(new, dict):
        for key in [*new, *(k for k in old if k not in new)]:
            where = f"{path}.{key}" if path else str(key)
            if key not in old or key not in new:
                return where
            found = _difference(old[key], new[key], where)
            if found:
                return found
        return None
    if isinstance(old, list) and isinstance(new, list):
        for i, (a, b) in enumerate(zip(old, new)):
            found = _difference(a, b, f"{path}[{i}]")
            if found:
                return found
        return None if len(old) == len(new) else f"{path}[{min(len(old), len(new))}]"
    return None if old == new and type(old) is type(new) else path or "(the whole text)"


def _only_read_keys_differ(stored_text: str, campaign_text: str) -> bool:
    """Whether the two campaigns' mappings differ in READ_ONLY_KEYS alone."""
    stored, ours = campaign_mapping(stored_text), campaign_mapping(campaign_text)
    keys = set(stored) | set(ours)
    return bool(stored) and all(stored.get(k) == ours.get(k) for k in keys if k not in READ_ONLY_KEYS)


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
