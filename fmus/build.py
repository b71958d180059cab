"""Build step: pack each slave with the code it needs into ``fmus/build/<Name>.fmu``.

Layout of an FMU::

    modelDescription.xml                 generated from the model's variable table
    binaries/linux64/<Name>.so           our C shim (shim/*.c), compiled here
    binaries/linux64/pythonfmu-export.so pythonfmu's binary, which the shim forwards to
    resources/slavemodule.txt            -> <Name>_<hash>
    resources/<Name>_<hash>.py           pythonfmu entry point: makes the slave class
    resources/agilesat_<hash>/           our code: the model, the slave and their imports
    resources/pythonfmu/                 pythonfmu's Python package (as pythonfmu packs it)
    documentation/index.html             the variable table

pythonfmu runs every FMU in one interpreter with one ``sys.modules``: same-named modules
of two FMUs would resolve to whichever was imported first, and a host that imported our
package would shadow the FMU's copy.  So the code is packed under a package named after
the hash of its content: two FMUs share a module only if its bytes are identical.  The
archive is deterministic (sorted entries, fixed timestamps): same sources, same file.
"""

from __future__ import annotations

import functools
import hashlib
import io
import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import warnings
import zipfile
from collections.abc import Callable
from html import escape
from importlib import metadata
from pathlib import Path

from ..components.runtime import jit
from ..components.runtime.cache import cache_root
from ..components.runtime.toolchain import c_compiler, replacing
from . import FMUS, model_class, native, protocol
from .model_description import model_description
from .source_facts import facts

FMUS_DIR = Path(__file__).resolve().parent
BUILD_DIR = FMUS_DIR / "build"
SHIM_DIR = FMUS_DIR / "shim"
#: the shim's translation units: the FMI forwarding and the fast paths
SHIM_C_FILES = (SHIM_DIR / "agilesat_fmi2.c", SHIM_DIR / "fast_paths.c")
#: the header generated from protocol.py (`agilesat generate`)
PROTOCOL_HEADER = SHIM_DIR / "protocol.h"
SHIM_SOURCES = (*SHIM_C_FILES, SHIM_DIR / "shim.h", SHIM_DIR / "fmi2_abi.h", PROTOCOL_HEADER)
#: the shim's libraries, kept as dependencies whether or not a symbol binds there: a glibc
#: older than 2.34 has dlopen and pthread_once there (shim/shim.h, symbol versions)
SHIM_LIBRARIES = ("-Wl,--no-as-needed", "-l:libdl.so.2", "-l:libpthread.so.0")
PLATFORM = "linux64"
#: the newest symbol versions pythonfmu's binary (pythonfmu-export.so) needs of the system,
#: as ``objdump -T`` lists them (tests/fmus/test_portability.py checks them on the binary):
#: glibc 2.32 (__libc_single_threaded), libstdc++ of GCC 12 (GLIBCXX_3.4.30:
#: std::condition_variable::wait).  The shim needs glibc 2.2.5 (shim/shim.h).
PYTHONFMU_NEEDS = ("GLIBC_2.32", "GLIBCXX_3.4.30")
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)


class BuildError(RuntimeError):
    pass


def build_all(out_dir: Path = BUILD_DIR, names=None, force: bool = False) -> list[Path]:
    """Build the named FMUs (default all) that are missing or stale; return their paths."""
    return [build_fmu(name, out_dir, force) for name in (names or FMUS)]


def build_fmu(name: str, out_dir: Path = BUILD_DIR, force: bool = False) -> Path:
    if name not in FMUS:
        raise BuildError(f"unknown FMU {name!r}; known: {', '.join(FMUS)}")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    target = out_dir / f"{name}.fmu"
    sources, digest = _sources(name)
    if not force and is_current(target, name, digest):
        return target
    package = f"agilesat_{digest}"
    entry = _entry_module(name, package)
    model = model_class(name)
    entries = fmu_entries(name, model, digest, sources, entry, out_dir)
    write_archive(target, entries)
    if jit.kernels(sys.modules[model.__module__]):
        native = compile_kernels(target, name, package)
        if native:
            binaries = {f"binaries/{PLATFORM}/{file}": data for file, data in native.items()}
            write_archive(target, {**entries, **binaries})
    return target


def fmu_entries(name: str, model, digest: str, sources: dict, entry_module: str, out_dir) -> dict:
    """The files of the FMU ``name`` of ``model`` (see the module): ``sources`` our code
    packed (:func:`_sources`), ``entry_module`` the module pythonfmu imports; the shim is
    compiled once into ``out_dir``."""
    package, entry = f"agilesat_{digest}", f"{name}_{digest}"
    binaries = {
        f"binaries/{PLATFORM}/{name}.so": _shim_library(Path(out_dir)).read_bytes(),
        f"binaries/{PLATFORM}/pythonfmu-export.so": _pythonfmu_binary().read_bytes(),
    }
    entries = {
        "modelDescription.xml": description_xml(name, digest, model, binaries),
        **binaries,
        "resources/slavemodule.txt": entry.encode(),
        f"resources/{entry}.py": entry_module.encode(),
        f"resources/{package}/__init__.py": b"",
        "documentation/index.html": documentation(name, model).encode(),
    }
    for relative, path in sources.items():
        entries[f"resources/{package}/{relative}"] = path.read_bytes()
    for path in sorted(_pythonfmu_dir().glob("*.py")):
        entries[f"resources/pythonfmu/{path.name}"] = path.read_bytes()
    return entries


_COMPILE_KERNELS = """
import importlib, os, pathlib, sys
os.environ["AGILESAT_JIT_AFTER"] = "0"
folder, name, package, module, out, compiler = sys.argv[1:]
sys.path.insert(0, folder + "/resources")
model = getattr(importlib.import_module(package + ".components." + module), name)
if out:  # first: numba compiles nothing before, so the same sources give the same library
    native = importlib.import_module(package + ".fmus.native")
    try:
        for file, data in native.build_in([model], compiler).items():
            pathlib.Path(out, file).write_bytes(data)
    except Exception as exc:
        print(f"{type(exc).__name__}: {exc}".strip().splitlines()[0], file=sys.stderr)
if not (out and os.listdir(out)):  # without them, the compile cache serves its runs
    model().start(0.0).advance(0.0, 0.1)
    c_entries = importlib.import_module(package + ".fmus.c_entries")
    for entry in c_entries.of(model)[:2]:
        if entry is not None:
            entry.address
"""


def compile_kernels(fmu: Path, name: str, package: str) -> dict[str, bytes]:
    """The library of the FMU's C entries compiled ahead of time and its manifest
    (:mod:`.native`): load its code from an extraction, as a host does, in a fresh process
    of this Python, run its model at the defaults for one step, compile.  Where that cannot
    be made (no C compiler, another architecture), {} and the compile cache of its kernels
    filled instead (components/runtime/jit.py: keyed on content, so any later extraction
    of this FMU loads the compiled kernels instead of compiling them)."""
    kept = cache_root() / "native" / package  # the package's name: its content's hash
    built = _kept(kept)
    if built:
        return built
    compiler = c_compiler()
    with tempfile.TemporaryDirectory() as out:
        result = subprocess.run(
            [sys.executable, "-c", _COMPILE_KERNELS, str(_extraction(fmu, package)), name,
             package, FMUS[name], out if compiler else "", compiler or ""],
            capture_output=True,
            text=True,
            env={**os.environ, "AGILESAT_NATIVE": "0"},
        )  # fmt: skip
        if result.returncode != 0:
            raise BuildError(f"compiling the kernels of {fmu} failed:\n{result.stderr}")
        built = {path.name: path.read_bytes() for path in sorted(Path(out).iterdir())}
        if built:
            _keep(kept, Path(out))
        if compiler and not built:
            warnings.warn(
                f"agilesat build: {fmu.name} has no ahead-of-time C entries "
                f"({result.stderr.strip() or 'none made'}): numba compiles them where it runs",
                stacklevel=2,
            )
        return built


def _kept(folder: Path) -> dict[str, bytes]:
    """The library and manifest an earlier build of the same content made (the same
    bytes: the build is deterministic), if whole: {} if absent, damaged or unreadable."""
    try:
        files = {path.name: path.read_bytes() for path in sorted(folder.iterdir())}
        manifest = json.loads(files[native.MANIFEST])
        whole = hashlib.sha256(files[native.LIBRARY]).hexdigest() == manifest["sha256"]
    except (OSError, KeyError, ValueError, TypeError):
        return {}
    return files if whole and len(files) == 2 else {}


def _keep(folder: Path, made: Path) -> None:
    """Keep a build's library and manifest for the next build of the same content (in one
    step; an unwritable cache keeps nothing)."""
    try:
        folder.parent.mkdir(parents=True, exist_ok=True)
        staged = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", dir=folder.parent))
    except OSError:
        return
    try:
        for path in made.iterdir():
            shutil.copyfile(path, staged / path.name)
        shutil.rmtree(folder, ignore_errors=True)  # a damaged one
        staged.rename(folder)
    except OSError:  # another build kept it first
        shutil.rmtree(staged, ignore_errors=True)


def _extraction(fmu: Path, package: str) -> Path:
    """The FMU unpacked where its content names it (the compiled code's error messages
    name its source files: the same sources make the same library); a private folder
    where that one cannot be made."""
    folder = Path(tempfile.gettempdir()) / "agilesat-build" / package
    if not folder.is_dir():
        unpacked = Path(tempfile.mkdtemp(prefix=f".{package}.", dir=folder.parent.parent))
        zipfile.ZipFile(fmu).extractall(unpacked)
        try:
            folder.parent.mkdir(exist_ok=True)
            unpacked.rename(folder)  # in one step: a parallel build sees all of it or none
        except OSError:  # another build made it first, or no permission
            if not folder.is_dir():
                return unpacked
            shutil.rmtree(unpacked, ignore_errors=True)
    return folder


def description_xml(name: str, digest: str, model, binaries: dict[str, bytes]) -> bytes:
    """The model description of FMU ``name`` of ``model`` built from the sources of hash
    ``digest``, with the SHA-256 of its ``binaries`` (an exported FMU's is this one with
    its values written in: fmus/configure.py)."""
    return model_description(
        name,
        model,
        protocol.fmu_guid(name, digest),
        (model.__doc__ or name).strip().splitlines()[0] + " " + requirements()[0],
        f"agilesat {metadata.version('agilesat')} (pythonfmu {metadata.version('pythonfmu')})",
        binaries,
    )


def write_archive(target: Path, entries: dict[str, bytes]) -> Path:
    """A deterministic zip (sorted entries, fixed timestamps), written atomically (under a
    name unique to this writer, then renamed: parallel builds never share a file)."""
    with replacing(target) as partial:
        partial.write_bytes(archive_bytes(entries))
    return target


def archive_bytes(entries: dict[str, bytes]) -> bytes:
    """A deterministic zip of ``entries`` (sorted, fixed timestamps), in memory."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        for arcname in sorted(entries):
            info = zipfile.ZipInfo(arcname, _ZIP_TIME)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = (0o755 if arcname.endswith(".so") else 0o644) << 16
            archive.writestr(info, entries[arcname])
    return buffer.getvalue()


def _entry_module(name: str, package: str) -> str:
    """The module pythonfmu imports (resources/slavemodule.txt names it)."""
    return (
        f"# pythonfmu entry point of the {name} FMU (generated by agilesat build).\n"
        "# pythonfmu 0.7.0 runs this file once per instantiation with the module's __dict__ as\n"
        "# globals, then drops a reference to that dict that it never took (Py_DECREF of the\n"
        "# borrowed PyModule_GetDict result; NTNU-IHB/PythonFMU#228): the dict would be freed\n"
        "# while in use.  Each run adds the reference back, so the count is balanced per\n"
        "# instantiation (only the import itself keeps one: nothing grows).\n"
        "# pythonfmu instantiates the Fmi2Slave subclass it finds here, made by slave_class.\n"
        "import ctypes\n"
        "ctypes.pythonapi.Py_IncRef(ctypes.py_object(globals()))\n"
        f"from {package}.fmus import slave_class as _slave_class  # noqa: E402\n"
        f"{name} = _slave_class({name!r})\n"
        "del _slave_class\n"
    )


def is_current(path: Path, name: str, digest: str | None = None) -> bool:
    """True if ``path`` is an FMU built from the current sources of ``name``."""
    digest = digest or _sources(name)[1]
    try:
        with zipfile.ZipFile(path) as archive:
            return f"resources/{name}_{digest}.py" in archive.namelist()
    except (OSError, zipfile.BadZipFile):
        return False


def _sources(name: str, modules=None) -> tuple[dict[str, Path], str]:
    """Files packed as our code (relative path -> file) and the content hash of the FMU.

    Our code is the FMU's model module, the generic slave and the registry that makes the
    slave class (``fmus/__init__.py``), and everything they import from our packages,
    followed through relative imports (``from ..components.cmg_cluster import ...``);
    ``modules`` (paths like 'components/noise.py') instead of the model module: those a
    model of a user's imports (:mod:`.user_models`).
    """
    files: dict[str, Path] = {}
    pending = ["fmus/__init__.py", "fmus/slave.py", *(modules or [f"components/{FMUS[name]}.py"])]
    while pending:
        relative = pending.pop()
        if relative in files:
            continue
        path = FMUS_DIR.parent / relative
        files[relative] = path
        pending += _relative_imports(relative, path)
        parts = relative.split("/")
        pending += [f"{'/'.join(parts[:k])}/__init__.py" for k in range(1, len(parts))]
    digest = hashlib.sha256()
    for relative, path in sorted(files.items()):
        digest.update(relative.encode() + b"\0" + path.read_bytes() + b"\0")
    for path in (*SHIM_SOURCES, FMUS_DIR / "build.py", FMUS_DIR / "model_description.py"):
        digest.update(path.read_bytes())
    digest.update(_toolchain_digest())
    return files, digest.hexdigest()[:12]


@functools.cache
def _toolchain_digest() -> bytes:
    """What every FMU's content depends on besides our code (once per process): the
    pythonfmu binary and version, the Python runtime the shim starts."""
    return hashlib.sha256(
        _pythonfmu_binary().read_bytes()
        + metadata.version("pythonfmu").encode()
        + metadata.version("numba").encode()  # the kernels' library (native.py)
        + "\0".join(python_runtime()).encode()
    ).digest()


def _relative_imports(relative: str, path: Path, root: Path = FMUS_DIR.parent) -> list[str]:
    """Our modules a module imports relatively, as paths like 'components/cmg_cluster.py'
    (relative to ``root``; a package's modules with its ``__init__.py``)."""
    package = "/".join(relative.split("/")[:-1])
    found = []
    for level, name, names in facts(path.read_text(), str(path))["imports"]:
        base = package.split("/")[: len(package.split("/")) - level + 1]
        module = "/".join(base + (name.split(".") if name else []))
        if (root / module).is_dir():  # from ..components.analysis import x
            found.append(f"{module}/__init__.py")
            for alias in names:  # from . import slave, analysis
                if (root / module / f"{alias}.py").is_file():
                    found.append(f"{module}/{alias}.py")
                elif (root / module / alias).is_dir():
                    found.append(f"{module}/{alias}/__init__.py")
        else:  # from .cmg_cluster import x
            found.append(f"{module}.py")
    return found


@functools.cache
def _pythonfmu_dir() -> Path:
    """The installed pythonfmu package (from its distribution, not the import path, which
    an FMU loaded in this process may have shadowed)."""
    return Path(metadata.distribution("pythonfmu").locate_file("pythonfmu"))


def _pythonfmu_binary() -> Path:
    path = _pythonfmu_dir() / "resources" / "binaries" / PLATFORM / "libpythonfmu-export.so"
    if not path.exists():
        raise BuildError(f"pythonfmu has no {PLATFORM} binary at {path}")
    return path


def python_runtime() -> tuple[str, str, str]:
    """(shared libpython, python executable, "X.Y") the FMUs start in a host without
    Python.

    The executable is this environment's own (``sys.executable``, not resolved: a virtual
    environment is recognised by the pyvenv.cfg beside its ``bin/``), named ``python`` where
    that is the same file: ``.venv/bin/agilesat`` runs ``python3``, ``.venv/bin/python -m
    pytest`` ``python``, and the FMUs one built were stale for the other (every FMU built
    again).  The library is "" when this Python has no shared libpython (then only Python
    hosts can load the FMUs).
    """
    executable = os.path.abspath(sys.executable)
    plain = os.path.join(os.path.dirname(executable), "python")
    if os.path.realpath(plain) == os.path.realpath(executable):
        executable = plain
    library = ""
    if sysconfig.get_config_var("Py_ENABLE_SHARED"):
        path = Path(
            sysconfig.get_config_var("LIBDIR") or "", sysconfig.get_config_var("INSTSONAME") or ""
        )
        library = str(path) if path.is_file() else ""
    return library, executable, "{}.{}".format(*sys.version_info)


def _shim_library(out_dir: Path) -> Path:
    """Compile the shim once per source version and Python runtime (cached in
    <out_dir>/.shim/)."""
    if PROTOCOL_HEADER.read_text() != protocol.header():
        raise BuildError(f"{PROTOCOL_HEADER} is out of date: run `agilesat generate`")
    flags = [*shim_flags(*python_runtime()), *map(str, SHIM_C_FILES), *SHIM_LIBRARIES]
    digest = hashlib.sha256(
        b"".join(p.read_bytes() for p in SHIM_SOURCES) + "\0".join(flags).encode()
    ).hexdigest()[:12]
    library = out_dir / ".shim" / f"agilesat_fmi2_{digest}.so"
    if library.exists():
        return library
    library.parent.mkdir(parents=True, exist_ok=True)
    compiler = c_compiler()
    if not compiler:
        raise BuildError(
            "building FMUs needs a C compiler (cc or gcc, or set CC) for the FMI shim fmus/shim/"
        )
    with replacing(library) as partial:
        command = [compiler, "-O2", *flags, "-o", str(partial)]
        result = subprocess.run(command, capture_output=True, text=True)
        if result.returncode != 0:
            raise BuildError(
                f"compiling the FMI shim failed:\n{' '.join(command)}\n{result.stderr}"
            )
    return library


def shim_flags(libpython: str, python: str, version: str) -> list[str]:
    """The compiler flags that make the shim's sources (SHIM_C_FILES) a shared library, for
    a Python runtime (:func:`python_runtime`).  ``-z nodelete``: a host that unloads the
    library between two instances (ECOS loads and unloads an FMU's library per instance)
    keeps its instance registry and pythonfmu's handles alive, as pythonfmu's own binary
    is (its GNU-unique C++ symbols make it NODELETE).  ``-ffp-contract=off``: no fused
    multiply-add, so what the C step path computes beside the Python
    (``inputs_to_step_end``) is the same bits."""
    defines = [
        f"-DAGILESAT_{key}={_c_string(value)}"
        for key, value in (
            ("LIBPYTHON", libpython),
            ("PYTHON", python),
            ("PYTHON_VERSION", version),
            ("PYTHON_MINIMUM", python_minimum()),
        )
    ]
    return [
        "-shared",
        "-fPIC",
        "-ffp-contract=off",
        "-fvisibility=hidden",
        "-Wl,-z,nodelete",
        *defines,
    ]


def python_minimum() -> str:
    """The oldest Python agilesat runs on, "X.Y" (its Requires-Python)."""
    return metadata.metadata("agilesat")["Requires-Python"].lstrip(">=~ ")


def generated_files() -> dict[Path, Callable[[], bytes]]:
    """The files `agilesat generate` writes from the tables: the FMUs' interfaces and the
    shim's protocol header."""
    return {
        FMUS_DIR / "INTERFACES.md": lambda: interfaces_markdown().encode(),
        PROTOCOL_HEADER: lambda: protocol.header().encode(),
    }


def _c_string(text: str) -> str:
    """A C string literal (for a -D definition)."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def interface_rows(model):
    """(name, causality, type, unit, start, description) for docs, from the table."""
    for v in model.VARIABLES:
        shape = f"[{','.join(map(str, v.shape))}]" if v.shape else ""
        start = "" if v.causality == "output" else _short(v.start)
        unit = v.unit if v.type == "Real" else ""
        notes = []
        if v.causality == "input":
            notes.append("required" if v.required else f"optional, {v.optional}")
        if v.depends:
            notes.append("feedthrough from " + ", ".join(v.depends))
        if v.derivative_of:
            notes.append(f"the derivative of {v.derivative_of} (FMI input/output derivatives)")
        description = v.description + (f" ({'; '.join(notes)})" if notes else "")
        yield f"{v.name}{shape}", v.causality, v.type, unit, start, description


def interfaces_markdown() -> str:
    """fmus/INTERFACES.md: every FMU's variables, from the variable tables."""
    parts = [
        "# FMU interfaces\n\nGenerated from the variable tables by `agilesat generate`; "
        "do not edit.  Units are SI (angles in rad); structured names are 1-based "
        "(`w_BI_B[1]`, `inertia[2,3]`).\n"
    ]
    for name in FMUS:
        model = model_class(name)
        doc = (model.__doc__ or "").strip()
        parts.append(
            f"\n## {name}\n\n{doc}\n\n| variable | causality | type | unit | "
            "start | description |\n|---|---|---|---|---|---|"
        )
        for row in interface_rows(model):
            parts.append("| " + " | ".join(str(c).replace("|", "\\|") for c in row) + " |")
    return "\n".join(parts) + "\n"


def _short(value) -> str:
    text = repr(value if not hasattr(value, "tolist") else value.tolist())
    return text if len(text) <= 40 else text[:37] + "..."


def requirements() -> tuple[str, list[str]]:
    """What an FMU needs where it runs: (one line for the model description, the points of
    its documentation/index.html), from the package's metadata, the Python building it and
    what pythonfmu's binary needs (docs/hosts.md says the same)."""
    _, python, version = python_runtime()
    needed = {r.split(">")[0]: r for r in metadata.requires("agilesat") or []}
    numpy, sgp4 = needed.get("numpy", "numpy"), needed.get("sgp4", "sgp4")
    glibc, libstdcxx = (v.split("_")[1] for v in PYTHONFMU_NEEDS)
    line = (
        f"Needs Python {metadata.metadata('agilesat')['Requires-Python']} with {numpy}; in a "
        "host without Python, the libpython and the environment of one such Python, of one "
        f"minor version (built with Python {version}; set AGILESAT_LIBPYTHON and "
        "AGILESAT_PYTHON); "
        f"Linux x86-64, glibc >= {glibc}, libstdc++ >= GLIBCXX_{libstdcxx} (see "
        "documentation/index.html)."
    )
    points = [
        f"In a Python host (FMPy, libcosimpy, ecospy, agilesat's master) the FMU runs in the "
        f"host's own interpreter: Python {metadata.metadata('agilesat')['Requires-Python']} "
        f"with {numpy} ({sgp4} for an OrbitEnvironment given a TLE; numba, optional, "
        "compiles the models' hot loops in long runs).",
        f"In a host without Python (a C/C++ tool, OMSimulator, libcosim's or ECOS's command "
        f"line) the FMU starts the Python it was built with, Python {version}: the shared "
        f"libpython and the environment of {python}.  On another machine, any Python "
        f"{python_minimum()} or later will do: make an environment of it with numpy (and "
        "sgp4) and set AGILESAT_LIBPYTHON to its shared libpython (libpython3.X.so.1.0) and "
        "AGILESAT_PYTHON to the environment's python, both of one minor version; anything "
        "missing or mismatched is named by fmi2Instantiate through the host's logger.",
        f"Linux x86-64 with glibc >= {glibc} and the libstdc++ of GCC 12 or later "
        f"(GLIBCXX_{libstdcxx}): what pythonfmu's binary needs (Debian 12, Ubuntu 22.04 and "
        "later; not Ubuntu 20.04, RHEL 8 or RHEL 9).  The FMU's own binary needs glibc 2.2.5.",
    ]
    return line, points


def _table(header, rows) -> str:
    cells = ["".join(f"<th>{escape(h)}</th>" for h in header)]
    cells += ["".join(f"<td>{escape(str(c))}</td>" for c in row) for row in rows]
    return "<table border='1'>" + "\n".join(f"<tr>{c}</tr>" for c in cells) + "</table>"


def configured_section(configured: dict) -> str:
    """The part of documentation/index.html that lists the values an exported FMU was
    configured with (fmus/configure.py)."""
    return (
        "<h2>Configured defaults</h2><p>Exported by agilesat with these values as its "
        "defaults (the start values of its model description, and the model's values "
        "at instantiation); the package's parameter set gives them too.</p>"
        + _table(("name", "value"), sorted(configured.items()))
    )


def documentation(name: str, model) -> str:
    """documentation/index.html: the model's docstring, what the FMU needs, its variables
    (an exported FMU adds the values it was configured with before them:
    :func:`configured_section`)."""
    points = "".join(f"<li>{escape(point)}</li>" for point in requirements()[1])
    parts = [
        f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{name}</title></head>",
        f"<body><h1>{name}</h1><pre>{escape(model.__doc__ or '')}</pre>",
        f"<h2>What this FMU needs</h2><ul>{points}</ul>",
    ]
    header = ("name", "causality", "type", "unit", "start", "description")
    parts.append(f"<h2>Variables</h2>{_table(header, interface_rows(model))}</body></html>\n")
    return "".join(parts)


if __name__ == "__main__":
    for built in build_all(names=sys.argv[1:] or None, force=True):
        print(built)
