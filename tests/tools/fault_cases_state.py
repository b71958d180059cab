"""Fault injection on what an FMU loads and restores: tampered FMU states, a GUID that is
not the binary's, a damaged shim, a corrupted compile cache.

``CASES`` as in ``fault_cases_fmu`` (each returns ``{"fault", "expected", "observed",
"ok"}``).  The state cases drive a built FMU in a separate process through a plain fmpy
host (``python fault_cases_state.py CASE ARGS`` prints the child's findings as JSON); the
others run ``agilesat run`` on an edited copy of scan_pitch.
"""

from __future__ import annotations

import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
BUILD = Path(os.environ.get("AGILESAT_FAULT_FMUS", ROOT / "fmus" / "build"))
CLI = [sys.executable, "-m", "agilesat.orchestration"]
ERROR = 3


def _child(case: str, *args, env=None) -> tuple[dict | None, str]:
    """A case of this file in a child process (fault_cases_fmu's, with this script)."""
    sys.path.insert(0, str(HERE))
    from fault_cases_fmu import _child as child

    return child(case, *args, timeout=600, script=Path(__file__), env=env)


# -- tampered FMU states ------------------------------------------------------------------
#: (FMU, tampering): each one a state taken after five steps, decoded, changed, encoded
TAMPERINGS = {
    "CmgCluster": [
        "geometry.G shrunk to 5 of 6 rows",
        "geometry.S and geometry.T shrunk to 5 of 6 rows",
        "geometry.st cut to 30 of 36 values",
        "state cut to 40 of 52 values",
        "attribute 'output' (shadows the method)",
        "attribute 'INITIAL_STATE_DEPENDS' (shadows the class's)",
        "an attribute the model does not have",
        "geometry of another class (a dict)",
    ],
    "SatelliteDynamics": [
        "state cut to 30 of 36 values",
        "state as float32",
        "state with a NaN",
        "t as a string",
        "a parameter NaN in the value array",
        "state left out",
    ],
}


def _tamper(model_state, wrapper, what: str):
    values, strings, attributes = model_state
    attributes = dict(attributes)
    if what.startswith("geometry."):
        geometry = attributes["geometry"]
        for name in ("G", "S", "T") if "rows" in what else ():
            if name in what.split(" shrunk")[0]:
                setattr(geometry, name, getattr(geometry, name)[:5].copy())
        if "st cut" in what:
            geometry.st = geometry.st[:30].copy()
    elif what.startswith("state cut"):
        attributes["state"] = attributes["state"][: 30 if "30 of" in what else 40].copy()
    elif what == "state as float32":
        attributes["state"] = attributes["state"].astype(np.float32)
    elif what == "state with a NaN":
        attributes["state"] = attributes["state"].copy()
        attributes["state"][1] = np.nan
    elif what.startswith("attribute '"):
        attributes[what.split("'")[1]] = 1.0
    elif what == "an attribute the model does not have":
        attributes["gimbal_offset"] = 0.1
    elif what == "geometry of another class (a dict)":
        attributes["geometry"] = dict(vars(attributes["geometry"]))
    elif what == "t as a string":
        attributes["t"] = "0.25"
    elif what == "a parameter NaN in the value array":
        values = values.copy()
        values[0] = np.nan  # the first parameter of the table
    elif what == "state left out":
        del attributes["state"]
    else:
        raise KeyError(what)
    return (values, strings, attributes), wrapper


def _codec(data: bytes):
    """The FMU's own state format module (its package is loaded in this interpreter) and
    the identity and package a state names."""
    (n,) = struct.unpack_from("<I", data, 18 + 2)
    identity = data[24 : 24 + n].decode()
    package = identity.rsplit(".", 1)[0]
    return sys.modules[f"{package}.fmus.fmu_state"], identity, package


def tampered(name: str):
    """For each tampering of ``name``'s TAMPERINGS: deserialize it into an instance that
    has stepped, set it; then step that instance and a twin on, compare their outputs; and
    set it into a fresh instance."""
    sys.path.insert(0, str(HERE))
    import fault_cases_fmu as fmu_cases
    import fmi_host

    outcomes = {}
    for k, what in enumerate(TAMPERINGS[name]):
        a, twin = fmu_cases._ready(name, f"a{k}"), fmu_cases._ready(name, f"t{k}")
        inputs = fmi_host.plausible_inputs(a)
        for n in range(5):
            for fmu in (a, twin):
                assert fmu.set_real(inputs) == 0 and fmu.step(0.05 * n, 0.05) == 0
        data = fmu_cases._serialize(a, fmu_cases._state(a))
        codec, identity, package = _codec(data)
        model_state, wrapper = codec.decode(identity, data, package)
        bad = codec.encode(identity, _tamper(model_state, wrapper, what), package)
        status, state = fmu_cases._deserialize(a, bad)
        restored = status if status else a.dll.fmi2SetFMUstate(a.c, state)
        fresh = fmi_host.Fmu(fmu_cases._path(name), f"f{k}")
        status, state = fmu_cases._deserialize(fresh, bad)
        into_fresh = status if status else fresh.dll.fmi2SetFMUstate(fresh.c, state)
        outputs = a.names("output")
        same = True
        for n in range(5, 10):
            for fmu in (a, twin):
                assert fmu.set_real(inputs) == 0
            steps = [a.step(0.05 * n, 0.05), twin.step(0.05 * n, 0.05)]
            same &= steps == [0, 0] and a.get_real(outputs) == twin.get_real(outputs)
        said = [m for s, m in a.messages if s >= ERROR]
        outcomes[what] = {
            "refused": restored,
            "refused_fresh": into_fresh,
            "then_same_as_twin": bool(same),
            "message": said[-1][:200] if said else "",
        }
    return outcomes


def _state_case(jit: str):
    env = {"AGILESAT_JIT_AFTER": "0"} if jit == "compiled" else {"AGILESAT_JIT": "0"}

    def case():
        observed, ok = [], True
        for name in TAMPERINGS:
            answer, process = _child("tampered", name, env=env)
            if answer is None:
                observed.append(f"{name}: {process}")
                ok = False
                continue
            for what, o in answer.items():
                good = (
                    o["refused"] == ERROR
                    and o["refused_fresh"] == ERROR
                    and o["then_same_as_twin"]
                    and "state" in o["message"]
                )
                ok &= good
                observed.append(
                    f"{name} {what}: set {o['refused']}, into a fresh instance "
                    f"{o['refused_fresh']}, steps after as the twin's: "
                    f"{o['then_same_as_twin']}" + ("" if good else " (!)")
                )
        return {
            "fault": f"FMU states tampered after decoding ({jit} kernels): "
            + "; ".join(f"{n}: {', '.join(t)}" for n, t in TAMPERINGS.items()),
            "expected": "fmi2Error naming what does not fit the model's own layout, from "
            "fmi2DeSerializeFMUstate or fmi2SetFMUstate (also into a fresh instance); "
            "the instance steps on exactly as a twin that never saw the state",
            "observed": "; ".join(observed),
            "ok": ok,
        }

    case.__name__ = f"tampered_states_{jit}"
    return case


# -- what the master loads: GUID, shim, cache ---------------------------------------------
def _run(ssd, out, *extra, env=None):
    return subprocess.run(
        [
            *CLI,
            "run",
            str(ssd),
            "--stop",
            "0.5",
            "--no-figures",
            "--no-report",
            "--out",
            str(out),
            *extra,
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        env={**os.environ, **(env or {})},
    )


def _exit(result) -> str:
    code = result.returncode
    return f"killed by signal {-code}" if code < 0 else f"exit {code}"


def _with_fmu(directory: Path, name: str, fmu: Path) -> Path:
    """A copy of scan_pitch.ssd in directory whose component ``name`` is ``fmu``."""
    import re

    sys.path.insert(0, str(HERE))
    from fault_cases_master import system_copy

    return system_copy(
        directory, lambda s: re.sub(rf'source="[^"]*/{name}.fmu"', f'source="{fmu}"', s)
    )


def _edited_fmu(source: Path, target: Path, edit) -> Path:
    """A copy of the FMU ``source`` with ``edit({member: bytes})`` applied, a valid zip."""
    with zipfile.ZipFile(source) as archive:
        members = {info.filename: archive.read(info) for info in archive.infolist()}
    edit(members)
    with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return target


def _text_section(elf: bytes) -> tuple[int, int]:
    """(file offset, size) of the .text section of a 64-bit little-endian ELF."""
    (shoff,) = struct.unpack_from("<Q", elf, 0x28)
    shentsize, shnum, shstrndx = struct.unpack_from("<HHH", elf, 0x3A)
    sections = [struct.unpack_from("<IIQQQQ", elf, shoff + k * shentsize) for k in range(shnum)]
    names = sections[shstrndx][4]
    for name, _, _, _, offset, size in sections:
        if elf[names + name : names + name + 6] == b".text\0":
            return offset, size
    raise ValueError("no .text section")


def _zero_text(data: bytes) -> bytes:
    """4 KiB zeroed from the start of the code."""
    offset, _ = _text_section(data)
    return data[:offset] + bytes(4096) + data[offset + 4096 :]


def guid_mismatch():
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        other = "{00000000-1111-2222-3333-444444444444}"

        def edit(members):
            text = members["modelDescription.xml"].decode()
            start = text.index('guid="') + 6
            members["modelDescription.xml"] = (
                text[:start] + other + text[text.index('"', start) :]
            ).encode()

        fmu = _edited_fmu(BUILD / "CmgCluster.fmu", tmp / "CmgCluster.fmu", edit)
        result = _run(_with_fmu(tmp, "CmgCluster", fmu), tmp / "out")
        said = next((l for l in result.stderr.splitlines() if other in l), "")
        ok = result.returncode == 1 and "is not this FMU's" in result.stderr
        return {
            "fault": "CmgCluster.fmu whose modelDescription.xml declares another GUID than the "
            "binary was built with, run in scan_pitch",
            "expected": "exit 1: fmi2Instantiate refused, naming both GUIDs (FMI 2.0: they "
            "must be identical)",
            "observed": f"{_exit(result)}: {said.strip()[:220] or result.stderr[-200:]}",
            "ok": ok,
        }


def damaged_shim():
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        library = "binaries/linux64/CmgCluster.so"

        def edit(members):
            members[library] = _zero_text(members[library])

        fmu = _edited_fmu(BUILD / "CmgCluster.fmu", tmp / "CmgCluster.fmu", edit)
        result = _run(_with_fmu(tmp, "CmgCluster", fmu), tmp / "out")
        ok = (
            result.returncode == 1
            and library in result.stderr
            and str(fmu) in result.stderr
            and "Traceback" not in result.stderr
        )
        return {
            "fault": "CmgCluster.fmu whose shim binaries/linux64/CmgCluster.so has 4 KiB of "
            "its code zeroed (a valid zip), run in scan_pitch",
            "expected": "exit 1 naming the FMU and its damaged binary before loading it; no "
            "segfault",
            "observed": f"{_exit(result)}: {result.stderr.strip().splitlines()[-1][:220]}"
            if result.stderr.strip()
            else _exit(result),
            "ok": ok,
        }


def _extraction(cache: Path, name: str) -> Path:
    import hashlib

    return cache / "fmus" / hashlib.sha256((BUILD / f"{name}.fmu").read_bytes()).hexdigest()


def _random_pyc_bodies(directory: Path) -> None:
    rng = np.random.default_rng(3)
    for pyc in directory.rglob("*.pyc"):
        data = pyc.read_bytes()
        pyc.write_bytes(data[:16] + rng.bytes(len(data) - 16))


def _numba_garbage(cache: Path) -> None:
    rng = np.random.default_rng(4)
    for entry in (cache / "numba").rglob("satellite_dynamics*"):
        entry.write_bytes(rng.bytes(entry.stat().st_size))


CORRUPTIONS = {
    "the unpacked shim of SatelliteDynamics truncated to half": lambda cache: (
        lambda so: so.write_bytes(so.read_bytes()[: so.stat().st_size // 2])
    )(_extraction(cache, "SatelliteDynamics") / "binaries/linux64/SatelliteDynamics.so"),
    "the unpacked shim of SatelliteDynamics with 4 KiB of its code zeroed": lambda cache: (
        lambda so: so.write_bytes(_zero_text(so.read_bytes()))
    )(_extraction(cache, "SatelliteDynamics") / "binaries/linux64/SatelliteDynamics.so"),
    "the compiled master loop zeroed": lambda cache: [
        so.write_bytes(bytes(so.stat().st_size)) for so in (cache / "loop").glob("*.so")
    ],
    "the numba cache files of SatelliteDynamics' kernels random bytes": _numba_garbage,
    "the compiled .pyc bodies of CmgCluster random": lambda cache: _random_pyc_bodies(
        _extraction(cache, "CmgCluster")
    ),
    "the model source of CmgCluster replaced": lambda cache: [
        source.write_text("raise SystemExit('replaced')\n")
        for source in _extraction(cache, "CmgCluster").rglob("cmg_cluster.py")
    ],
}


def corrupted_cache():
    """A run fills a fresh $AGILESAT_CACHE_DIR (kernels compiled from the first call);
    each corruption is made to a copy of it, and scan_pitch run again on that copy."""
    ssd = ROOT / "orchestration" / "systems" / "scan_pitch.ssd"
    with tempfile.TemporaryDirectory() as tmp:
        tmp, observed, ok = Path(tmp), [], True
        env = {"AGILESAT_CACHE_DIR": str(tmp / "cache"), "AGILESAT_JIT_AFTER": "0"}
        first = _run(ssd, tmp / "clean", env=env)
        clean = np.load(tmp / "clean" / "results.npz")["data"] if not first.returncode else None
        for k, (label, corrupt) in enumerate(CORRUPTIONS.items()):
            cache = shutil.copytree(tmp / "cache", tmp / f"cache{k}", symlinks=True)
            corrupt(cache)
            result = _run(ssd, tmp / f"run{k}", env={**env, "AGILESAT_CACHE_DIR": str(cache)})
            try:
                same = clean is not None and np.array_equal(
                    np.load(tmp / f"run{k}" / "results.npz")["data"], clean
                )
            except (OSError, ValueError, KeyError):
                same = False
            warned = [
                l.partition("agilesat: ")[2] for l in result.stderr.splitlines() if "damaged" in l
            ]
            good = result.returncode == 0 and same and bool(warned)
            ok &= good
            observed.append(
                f"{label}: {_exit(result)}, results as the clean run's: {same}"
                + (f", said: {warned[0].strip()[:160]}" if warned else ", said nothing")
                + ("" if good else " (!)")
            )
        return {
            "fault": "corrupted entries of the compile cache ($AGILESAT_CACHE_DIR): "
            + "; ".join(CORRUPTIONS),
            "expected": "each entry checked against its content hash before it is loaded: "
            "a warning naming the damaged entry, rebuilt, the run exits 0 with the clean "
            "run's results bit for bit; never a crash",
            "observed": "; ".join(observed),
            "ok": ok,
        }


CASES = [
    _state_case("python"),
    _state_case("compiled"),
    guid_mismatch,
    damaged_shim,
    corrupted_cache,
]


if __name__ == "__main__":
    case, *arguments = sys.argv[1:]
    print(json.dumps(globals()[case](*arguments)), flush=True)
