"""Cache entries checked against their SHA-256 before anything is loaded from them
(``components/runtime/cache.py``): sealed files, a digest beside a library, a manifest of an
unpacked FMU, numba's files (jit.py).  Whole runs on a damaged cache, in fresh processes:
``tests/tools/fault_cases_state.py`` (``corrupted_cache``)."""

import json
import zipfile

import numpy as np
import pytest

from agilesat.components.runtime import cache, jit
from agilesat.orchestration.cosim import fmu
from agilesat.orchestration.system.description import Description, content_key


def test_a_sealed_file_gives_its_body_back_only_intact():
    body = b"compiled" * 100
    sealed = cache.seal(body)
    assert cache.unseal(sealed) == body
    for damaged in (sealed[:-1], sealed[:20], b"", sealed[:40] + b"\0" + sealed[41:]):
        assert cache.unseal(damaged) is None


def test_a_digest_beside_a_file(tmp_path):
    library = tmp_path / "x.so"
    library.write_bytes(b"\x7fELF" + bytes(100))
    assert cache.damage_of_file(library) == "its SHA-256 (.sha256) is missing"
    cache.write_digest(library, library)
    assert cache.damage_of_file(library) == ""
    library.write_bytes(b"\x7fELF" + bytes(50))
    assert cache.damage_of_file(library) == "its content does not match its SHA-256"


def test_a_manifest_names_what_changed_or_went(tmp_path):
    (tmp_path / "a" / "b").mkdir(parents=True)
    (tmp_path / "a" / "b" / "m.py").write_text("x = 1\n")
    (tmp_path / "lib.so").write_bytes(b"code")
    cache.write_manifest(tmp_path)
    assert cache.damage_of_tree(tmp_path) == ""
    (tmp_path / "a" / "b" / "__pycache__").mkdir()  # written later by Python: not listed
    (tmp_path / "a" / "b" / "__pycache__" / "m.pyc").write_bytes(b"x")
    assert cache.damage_of_tree(tmp_path) == ""
    (tmp_path / "a" / "b" / "m.py").write_text("x = 2\n")
    assert cache.damage_of_tree(tmp_path) == "a/b/m.py does not match its SHA-256"
    (tmp_path / "a" / "b" / "m.py").unlink()
    assert cache.damage_of_tree(tmp_path) == "a/b/m.py is missing"
    (tmp_path / cache.MANIFEST).write_text("[")
    assert "manifest .agilesat-manifest.json is unreadable" in cache.damage_of_tree(tmp_path)


def _twice(x, y):
    return 2.0 * x + y


def test_damaged_numba_files_are_compiled_again_with_a_warning(tmp_path, monkeypatch):
    pytest.importorskip("numba")
    monkeypatch.setenv("AGILESAT_CACHE_DIR", str(tmp_path))
    assert jit.Kernel(_twice, 0)(1.0, 0.5) == 2.5  # compiled and cached
    files = sorted((tmp_path / "numba").rglob("*.nb*"))
    assert {f.suffix for f in files} == {".nbi", ".nbc"}
    for f in files:
        assert cache.unseal(f.read_bytes()) is not None
        f.write_bytes(np.random.default_rng(0).bytes(f.stat().st_size))
    with pytest.warns(UserWarning, match="damaged .*compiling again"):
        assert jit.Kernel(_twice, 0)(1.0, 0.5) == 2.5
    assert all(cache.unseal(f.read_bytes()) is not None for f in files)  # rewritten


def test_an_unpacked_fmu_is_checked_and_unpacked_again_when_damaged(fmus, tmp_path, monkeypatch):
    """Only unpacking is exercised here (nothing loaded in this process)."""
    monkeypatch.setenv("AGILESAT_CACHE_DIR", str(tmp_path))
    path = fmus["CmgCluster"]
    binaries = Description("c", path).binaries
    assert sorted(binaries) == [
        "binaries/linux64/CmgCluster.so",
        "binaries/linux64/pythonfmu-export.so",
    ]
    directory = fmu._extraction(content_key(path), str(path), binaries)
    listed = json.loads((tmp_path / "fmus" / content_key(path) / cache.MANIFEST).read_text())
    assert "binaries/linux64/CmgCluster.so" in listed and any(n.endswith(".pyc") for n in listed)
    shim = tmp_path / "fmus" / content_key(path) / "binaries/linux64/CmgCluster.so"
    shim.write_bytes(shim.read_bytes()[:1000])
    with pytest.warns(UserWarning, match="CmgCluster.so does not match its SHA-256"):
        again = fmu._extraction(content_key(path), str(path), binaries)
    assert again == directory and cache.damage_of_tree(shim.parents[2]) == ""


def test_an_fmu_whose_binary_is_not_what_it_declares_is_refused(fmus, tmp_path, monkeypatch):
    monkeypatch.setenv("AGILESAT_CACHE_DIR", str(tmp_path / "cache"))
    damaged = tmp_path / "CmgCluster.fmu"
    with zipfile.ZipFile(fmus["CmgCluster"]) as source, zipfile.ZipFile(damaged, "w") as target:
        for info in source.infolist():
            data = source.read(info)
            if info.filename.endswith("CmgCluster.so"):
                data = data[:4096] + bytes(4096) + data[8192:]
            target.writestr(info, data)
    with pytest.raises(fmu.DamagedFmuError, match="binaries/linux64/CmgCluster.so in .* does"):
        fmu._extraction(content_key(damaged), str(damaged), Description("c", damaged).binaries)
    assert not any((tmp_path / "cache" / "fmus").iterdir())  # nothing left behind
