"""Dataset folders: the same bytes on 1 or 2 workers or a Dask cluster, a killed run resumed,
a larger --n appended, refusals that leave the dataset as it was, and the reader."""

from __future__ import annotations

import hashlib
import pickle
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import seamtrack as st
from seamtrack.cli.main import main
from seamtrack.datasets.generate import generate
from seamtrack.datasets.layout import ARRAYS, chunk_path
from seamtrack.datasets.spec import TEMPLATE, DatasetSpec, parse_spec
from seamtrack.datasets.store import write_dataset
from seamtrack.errors import SeamtrackError

#: Every noise knob on (the template's), few rays: a chunk of 25 takes ~20 ms.
SMALL = {"rays": 128, "chunk_size": 25, "seed": 3}


def _digests(folder: Path) -> dict[str, str]:
    return {
        p.name: hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.iterdir())
        if p.is_file()
    }


@pytest.fixture(scope="module")
def serial(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("serial") / "data"
    write_dataset(parse_spec(SMALL), 110, out, workers=1)
    return out


def test_two_workers_write_the_same_bytes(serial: Path, tmp_path: Path) -> None:
    done = write_dataset(parse_spec(SMALL), 110, tmp_path / "data", workers=2)
    assert done["written"] == 5 and done["kept"] == 0
    ours, theirs = _digests(tmp_path / "data"), _digests(serial)
    assert sorted(ours) == [
        "chunk-000000.h5", "chunk-000001.h5", "chunk-000002.h5", "chunk-000003.h5",
        "chunk-000004.h5", "dataset.json", "spec.toml",
    ]  # fmt: skip
    assert ours == theirs


def test_a_dask_cluster_gives_the_same_bytes(serial: Path, tmp_path: Path) -> None:
    distributed = pytest.importorskip("dask.distributed")
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*heartbeat.*", category=UserWarning)
        cluster = distributed.LocalCluster(
            # threads start in a second, processes in ten; the chunks travel the same way
            n_workers=2,
            processes=False,
            threads_per_worker=1,
            dashboard_address=None,
        )
        try:
            write_dataset(parse_spec(SMALL), 110, tmp_path / "data",
                          scheduler=cluster.scheduler_address)  # fmt: skip
        finally:
            cluster.close(timeout=60)
    assert _digests(tmp_path / "data") == _digests(serial)


def test_the_files_hold_what_generate_draws(serial: Path) -> None:
    data = st.datasets.open(serial)
    assert len(data) == 110
    again = generate(parse_spec(SMALL), 50, 30)  # across the chunk boundary at 50
    got = data[50:80]
    for name in ARRAYS:
        np.testing.assert_array_equal(got[name], again[name], err_msg=name)


def test_a_larger_n_appends_and_a_smaller_one_keeps_everything(serial: Path, tmp_path: Path):
    out = tmp_path / "data"
    write_dataset(parse_spec(SMALL), 40, out)  # chunk 1 short: 15 of 25
    done = write_dataset(parse_spec(SMALL), 110, out)
    assert (done["kept"], done["written"]) == (1, 4)  # the short chunk is remade whole
    assert _digests(out) == _digests(serial)
    before = _digests(out)
    done = write_dataset(parse_spec(SMALL), 30, out)
    assert done["written"] == 0
    assert len(st.datasets.open(out)) == 110 and _digests(out) == before


#: Run in a child: the CLI's dataset command, where the writer stops half-way through chunk
#: ``HALTED`` (its temporary file begun, as a kill during a write leaves it), says so in the file
#: ``argv[1]`` and waits to be killed. The parent kills on that state, not on a count it must
#: catch in time: the outcome is the same on a fast or a slow machine.
HALTED = 3
_HALT_IN_A_WRITE = f"""
import sys, time
from pathlib import Path
from seamtrack.cli.main import main
from seamtrack.datasets import store

real = store.write_chunk

def write_chunk(out, spec, k, arrays):
    if k == {HALTED}:
        (Path(out) / f".chunk-{{k}}.halted.tmp").write_bytes(b"half an HDF5 file")
        Path(sys.argv[1]).touch()
        time.sleep(3600)
    return real(out, spec, k, arrays)

store.write_chunk = write_chunk
sys.exit(main(sys.argv[2:]))
"""


def test_a_killed_run_continues_where_it_stopped(tmp_path: Path) -> None:
    """SIGKILL while a chunk is being written; the rerun makes only the missing ones and
    the folder ends up byte for byte what an uninterrupted run writes."""
    spec = tmp_path / "spec.toml"
    spec.write_text("rays = 1024\nchunk_size = 10\nseed = 5\n")
    out = tmp_path / "data"
    halted = tmp_path / "halted"
    command = [sys.executable, "-c", _HALT_IN_A_WRITE, str(halted), "dataset", str(spec),
               "--n", "400", "--out", str(out), "-q"]  # fmt: skip
    proc = subprocess.Popen(command, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 300  # bounds the wait; it times nothing
        while not halted.exists() and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
        assert halted.exists(), "the run never reached the chunk it stops in"
    finally:
        proc.kill()
        proc.wait(timeout=30)
    assert sorted(out.glob("chunk-*.h5")) == [chunk_path(out, k) for k in range(HALTED)]
    assert list(out.glob(".chunk-*.tmp"))  # the killed write left its temporary file
    assert st.datasets.open(out).missing  # the reader says it is incomplete
    code = main(["dataset", str(spec), "--n", "400", "--out", str(out), "-q"])
    assert code == 0
    assert not list(out.glob(".*.tmp"))  # a half-written chunk of the killed run is gone
    fresh = tmp_path / "fresh"
    write_dataset(parse_spec({"rays": 1024, "chunk_size": 10, "seed": 5}), 400, fresh)
    assert _digests(out) == _digests(fresh)


def test_resuming_with_another_spec_is_refused_and_loses_nothing(
    serial: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = tmp_path / "other.toml"
    spec.write_text("rays = 128\nchunk_size = 25\nseed = 4\n")
    before = _digests(serial)
    code = main(["dataset", str(spec), "--n", "200", "--out", str(serial)])
    err = capsys.readouterr().err.splitlines()
    assert code == 2 and len(err) == 1
    assert "--out" in err[0] and "seed: 3 there, 4 here" in err[0]
    assert _digests(serial) == before


def test_a_folder_that_holds_something_else_is_refused(tmp_path: Path) -> None:
    (tmp_path / "notes.txt").write_text("mine\n")
    with pytest.raises(SeamtrackError) as info:
        write_dataset(DatasetSpec(), 10, tmp_path)
    assert info.value.field == "--out"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]


def test_reader_indexing_slicing_and_spec(serial: Path) -> None:
    data = st.datasets.open(serial)
    assert data.spec == parse_spec(SMALL)
    one = data[-1]
    assert one["index"] == 109 and one["points_laser"].shape == (128, 2)
    assert one["seam_point_laser"].shape == (2,) and one["T_seam_sensor"].shape == (4, 4)
    picked = data[[3, 60, 2]]
    assert picked["index"].tolist() == [3, 60, 2]
    np.testing.assert_array_equal(picked["params"][1], data[60]["params"])
    assert data[105:200]["index"].tolist() == list(range(105, 110))
    assert data[5:5]["points_laser"].shape == (0, 128, 2)
    assert data.column("joint").shape == (110,)
    assert data.names["joint_names"][int(one["joint"])] == data.joint_name(one["joint"])
    with pytest.raises(IndexError):
        data[110]
    # What a PyTorch DataLoader does with a map-style dataset: len, integer indexing,
    # pickling into worker processes, stacking the dicts.
    clone = pickle.loads(pickle.dumps(data))
    batch = {k: np.stack([clone[i][k] for i in range(4)]) for k in one}
    np.testing.assert_array_equal(batch["points_laser"], data[0:4]["points_laser"])


def test_info_and_template_from_the_command_line(
    serial: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["dataset", "--info", str(serial)]) == 0
    text = capsys.readouterr().out
    assert "110 samples of 128 rays" in text and "5 chunk files" in text
    target = tmp_path / "spec.toml"
    assert main(["dataset", "--template", "-o", str(target)]) == 0
    assert target.read_text() == TEMPLATE
    assert main(["dataset", "--template"]) == 0
    assert capsys.readouterr().out.endswith(TEMPLATE)


def test_datasets_is_a_lazy_attribute_of_the_package() -> None:
    code = (
        "import sys, seamtrack as st\n"
        "assert 'seamtrack.datasets' not in sys.modules\n"
        "st.datasets\n"
        "print(sorted(m for m in ('h5py', 'numba') if m in sys.modules))\n"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "[]"
