"""Groups replaced whole (uqflight.store.staged): a writer SIGKILLed while it wrote the staged group can
leave a link whose object header never reached the disk, which HDF5 can neither read, move nor delete
("bad object header version number": a resumed adaptive campaign died on it). Such a link is ignored by
the readers and skipped by the next writer. The damage is made as the kill leaves it: the staged group's
object header overwritten with zeros."""
import h5py
import numpy as np

from uqflight.designs.adaptive import IndexSet
from uqflight.store.rare import read_rare_event, write_rare_event
from uqflight.store.rounds import read_index_set, write_index_set
from uqflight.store.staged import staged_keys


def _damage_a_staged_group(path, name: str) -> None:
    with h5py.File(path, "r+") as f:
        staged = f.create_group(name)
        staged.create_dataset("index_set", data=np.zeros((1, 2), dtype=np.int64))
        address = h5py.h5o.get_info(staged.id).addr
    with open(path, "r+b") as raw:
        raw.seek(address)
        raw.write(b"\0" * 16)


def _state(rounds: int) -> IndexSet:
    return IndexSet([(0, 0), (1, 0)], [True, False], [0, rounds], [0.25, 0.5], rounds, "", 0.5)


def test_an_index_set_is_replaced_past_a_staged_group_a_kill_left_unreadable(tmp_path):
    path = tmp_path / "r.h5"
    with h5py.File(path, "w") as f:
        write_index_set(f, _state(1))
    _damage_a_staged_group(path, "design_next")
    with h5py.File(path, "r+") as f:
        try:
            del f["design_next"]
        except KeyError as exc:  # what the kill leaves: HDF5 itself cannot remove it
            assert "bad object header" in str(exc)
        assert read_index_set(f).rounds == 1  # the complete /design, the damaged link ignored
        write_index_set(f, _state(2))
        write_index_set(f, _state(3))
    with h5py.File(path, "r") as f:
        assert read_index_set(f) == _state(3)
        assert staged_keys(f, "design_next") == ["design_next"]  # the damaged link alone is left


def test_a_rare_event_record_is_written_past_a_damaged_staged_group(tmp_path):
    path = tmp_path / "r.h5"
    with h5py.File(path, "w") as f:
        f.create_dataset("samples/status", data=np.zeros(4, dtype=np.int8))
    _damage_a_staged_group(path, "rare_event_next")
    record = {"round_runs": [4], "round_probability": [0.25], "round_cov": [0.5], "batch_end": [4],
              "design_point_u": [1.0, 2.0], "design_point_xi": [1.0, 2.0], "design_point": [1.0, 2.0],
              "importance": [0.2, 0.8], "threshold": 3.0, "probability": 0.25, "lower": 0.1, "upper": 0.5,
              "cov": 0.5, "beta": 0.67, "budget": 10, "runs": 4, "failed": 0, "method": "subset_simulation",
              "of": "y", "side": "above", "stopped": "converged", "notes": []}
    with h5py.File(path, "r+") as f:
        assert read_rare_event(f, 4, 2) is None
        write_rare_event(f, record)
    with h5py.File(path, "r") as f:
        found = read_rare_event(f, 4, 2)
    assert found["probability"] == 0.25 and found["stopped"] == "converged"


def test_tsvd_factors_are_committed_past_a_damaged_staged_group(tmp_path):
    from uqflight.store.compressed import apply_staged, commit
    from uqflight.store.tsvd import IncrementalSVD

    path = tmp_path / "r.h5"
    U, s, V = np.eye(3, 2), np.array([2.0, 1.0]), np.eye(2)
    with h5py.File(path, "w") as f:
        f.create_group("tsvd").attrs["batch"] = 4
        commit(f["tsvd"].create_group("y"), IncrementalSVD.from_factors(U, s, V, 0.0), np.arange(2),
               np.zeros((0, 3)), np.zeros(0, dtype=np.int64))
    _damage_a_staged_group(path, "tsvd/y/next")
    with h5py.File(path, "r+") as f:
        group = f["tsvd/y"]
        apply_staged(group)  # reopening mends: the damaged link is no complete step, left as it is
        commit(group, IncrementalSVD.from_factors(U, 3 * s, V, 0.0), np.arange(2), np.zeros((0, 3)),
               np.zeros(0, dtype=np.int64))
    with h5py.File(path, "r") as f:
        np.testing.assert_array_equal(f["tsvd/y/s"][()], 3 * s)
        assert staged_keys(f["tsvd/y"], "next") == ["next"]
