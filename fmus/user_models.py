"""Models of a user, outside the repository, built into FMUs like ours: ``agilesat build
path/to/my_model.py``.

A model file is one Python module defining one or more classes on our model API::

    from agilesat.components.model import Model
    from agilesat.components.variables import input_, output, parameter

    class RateDamper(Model):
        "tau_cmd = -gain * w_BI_B"
        VARIABLES = (parameter("gain", 1.0, "N.m.s/rad", "rate gain"), ...)
        def step(self, t, dt): ...
        def output(self): ...

Each class becomes the FMU of its name, ``build/<Class>.fmu`` beside the file (or
``out_dir``), exactly as ours are made (:mod:`.build`): the model description from its
variable table (units, start values, output dependencies and InitialUnknowns), our C shim,
the generic slave, the code packed under a package named after its content hash.  The
model's imports of ``agilesat.components`` (``model``, ``variables``, ``noise``,
``rotations``, ...) are packed with it, rewritten to the packed copy, so the FMU needs no
agilesat installed where it runs; other imports must be installed packages (numpy).  It
is rebuilt only when its source, what it imports or the toolchain changed.

Stochastic models draw their noise from :mod:`agilesat.components.noise`: a pure function
of (seed, stream, index), so a run is reproducible from an Integer ``seed`` parameter, an
FMU state is plain data and a restored state continues bit for bit (the pattern:
docs/own-mission.md, "A model of your own").
"""

from __future__ import annotations

import ast
import hashlib
import importlib.util
import re
import sys
from pathlib import Path

from .build import BuildError, _sources, fmu_entries, is_current, write_archive

_ALLOWED = "agilesat.components"


def model_classes(path: Path) -> list[str]:
    """The names of the model classes a file defines (``class X(Model)``, read from its
    source)."""
    tree = _tree(path)
    return [
        node.name
        for node in tree.body
        if isinstance(node, ast.ClassDef) and any(_base_name(b) == "Model" for b in node.bases)
    ]


def build_model(path, name: str | None = None, out_dir=None, force: bool = False) -> list[Path]:
    """Build the FMU of each model class in ``path`` (or of class ``name``) into ``out_dir``
    (default ``build/`` beside the file), when missing or stale; return their paths."""
    path = Path(path).resolve()
    names = _chosen(path, name)
    out_dir = Path(out_dir) if out_dir is not None else path.parent / "build"
    source, modules = packed_source(path)
    files, digest = _digest(source, modules)
    built = []
    for cls in names:
        target = out_dir / f"{cls}.fmu"
        if force or not is_current(target, cls, digest):
            _write(target, path, cls, source, files, digest)
        built.append(target)
    return built


def model_fmu(path: Path, name: str | None = None, build: bool = True) -> Path:
    """The FMU of the model class ``name`` (the only one, if None) of ``path``: built if
    ``build`` (and missing or stale), else it must be there and current."""
    if build:
        return build_model(path, _one(path, name))[0]
    cls = _one(path, name)
    target = Path(path).resolve().parent / "build" / f"{cls}.fmu"
    digest = _digest(*packed_source(Path(path).resolve()))[1]
    if not is_current(target, cls, digest):
        raise BuildError(f"{target} is missing or older than {path} (agilesat build {path})")
    return target


def _digest(source: str, modules: list[str]) -> tuple[dict, str]:
    """(our code packed with a model: relative path -> file, the content hash of its FMU)
    for the model's packed ``source`` importing the component ``modules``."""
    files, base = _sources("", modules or ["components/model.py"])
    return files, hashlib.sha256(source.encode() + b"\0" + base.encode()).hexdigest()[:12]


def packed_digest(entries: dict[str, bytes], package: str) -> str:
    """The content hash the model FMU of ``entries`` (its files, ``package`` the folder of
    its code) would have if built now from the source packed in it: its own if these
    sources built it (fmus/configure.py).  Nothing in it is run."""
    source = next(
        data.decode()
        for path, data in entries.items()
        if path.startswith(f"{package}user/") and not path.endswith("/__init__.py")
    )
    modules = [path[len(package) :] for path in entries if path.startswith(f"{package}components/")]
    return _digest(source, sorted(modules))[1]


def _one(path: Path, name: str | None) -> str:
    names = _chosen(Path(path), name)
    if len(names) > 1:
        raise BuildError(
            f"{path} defines the models {', '.join(names)}: name one, {path}:{names[0]}"
        )
    return names[0]


def _chosen(path: Path, name: str | None) -> list[str]:
    found = model_classes(path)
    if not found:
        raise BuildError(f"{path}: no model class (class Name(Model), agilesat.components.model)")
    if name is not None and name not in found:
        raise BuildError(f"{path} has no model class {name!r}; it defines {', '.join(found)}")
    return [name] if name else found


def packed_source(path: Path) -> tuple[str, list[str]]:
    """(the model file's source with its ``agilesat.components`` imports made relative to
    the packed copy, the component modules it imports as 'components/x.py'); a
    BuildError naming the line of an import that cannot be packed."""
    source = path.read_text(encoding="utf-8")
    lines = source.splitlines(keepends=True)
    modules = []
    for node in ast.walk(_tree(path)):
        if not isinstance(node, (ast.Import, ast.ImportFrom)):
            continue
        at = f"{path}:{node.lineno}"
        if isinstance(node, ast.ImportFrom) and node.level:
            raise BuildError(f"{at}: a relative import: a model file is packed alone")
        names = (
            [node.module or ""]
            if isinstance(node, ast.ImportFrom)
            else [a.name for a in node.names]
        )
        for module in names:
            top = module.split(".")[0]
            if top == "agilesat" and not (module + ".").startswith(_ALLOWED + "."):
                raise BuildError(
                    f"{at}: imports {module}: a model imports only {_ALLOWED} (the "
                    "model API and plain NumPy physics)"
                )
            if top != "agilesat" and (path.parent / f"{top}.py").exists() and top != path.stem:
                raise BuildError(
                    f"{at}: imports {top}, a module beside the model that is not packed into "
                    "the FMU: put what it needs in the model's file, or install it as a package"
                )
            if top != "agilesat":
                continue
            if isinstance(node, ast.Import):
                raise BuildError(
                    f"{at}: write `from {module} import ...` (a model's imports of "
                    "agilesat are packed with it, as from-imports)"
                )
            modules += _component_modules(module, node.names)
            start = node.lineno - 1
            lines[start] = re.sub(
                r"\bfrom\s+agilesat\.components\b", "from ..components", lines[start], count=1
            )
            if "from ..components" not in lines[start]:
                raise BuildError(f"{at}: write the import on one line: from {module} import ...")
    return "".join(lines), sorted(set(modules))


def _component_modules(module: str, aliases) -> list[str]:
    """'agilesat.components.noise' -> ['components/noise.py']; 'agilesat.components' with
    ``import noise, rotations`` -> their files."""
    from . import _COMPONENTS

    rest = module[len(_ALLOWED) :].lstrip(".")
    if rest:
        found = [f"components/{rest.replace('.', '/')}.py"]
    else:
        found = [f"components/{a.name}.py" for a in aliases]
    for relative in found:
        if not (_COMPONENTS.parent / relative).is_file():
            raise BuildError(f"no module {relative} in agilesat (imported by a model)")
    return found


def _write(target: Path, path: Path, cls: str, source: str, files: dict, digest: str) -> None:
    """Write the FMU of model class ``cls`` of ``path`` (see the module)."""
    package = f"agilesat_{digest}"
    module = path.stem
    entry = (
        f"# pythonfmu entry point of the {cls} FMU (agilesat build of {path.name}).\n"
        "# The globals' reference count, as in agilesat's own FMUs (fmus/build.py).\n"
        "import ctypes\n"
        "ctypes.pythonapi.Py_IncRef(ctypes.py_object(globals()))\n"
        f"from {package}.fmus.slave import ModelSlave as _ModelSlave  # noqa: E402\n"
        f"from {package}.user.{module} import {cls} as _model  # noqa: E402\n"
        f"{cls} = type({cls!r}, (_ModelSlave,), {{'model_class': _model, "
        f"'__doc__': _model.__doc__}})\n"
        "del _ModelSlave, _model\n"
    )
    entries = fmu_entries(cls, _load(path, cls), digest, files, entry, target.parent)
    entries[f"resources/{package}/user/__init__.py"] = b""
    entries[f"resources/{package}/user/{module}.py"] = source.encode()
    target.parent.mkdir(parents=True, exist_ok=True)
    write_archive(target, entries)
    _validate(target)


def _load(path: Path, cls: str):
    """The model class, imported from the file in this process."""
    if not path.stem.isidentifier():
        raise BuildError(f"{path}: a model file's name must be a Python identifier")
    name = f"agilesat_model_{hashlib.sha256(str(path).encode()).hexdigest()[:8]}_{path.stem}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)  # type: ignore[union-attr]
    except Exception as exc:
        del sys.modules[name]
        raise BuildError(f"{path}: importing it failed: {type(exc).__name__}: {exc}") from exc
    return getattr(module, cls)


def _validate(fmu: Path) -> None:
    """fmpy's validation of the model description (variables, units, ModelStructure,
    InitialUnknowns); a BuildError listing the problems, and no FMU left behind."""
    from fmpy.validation import validate_fmu

    problems = validate_fmu(str(fmu))
    if problems:
        fmu.unlink(missing_ok=True)
        raise BuildError(f"{fmu} does not validate:\n  " + "\n  ".join(problems))


def _tree(path: Path) -> ast.Module:
    try:
        return ast.parse(path.read_text(encoding="utf-8"), str(path))
    except (OSError, SyntaxError, UnicodeDecodeError) as exc:
        raise BuildError(f"{path}: cannot read the model: {exc}") from None


def _base_name(node) -> str:
    return node.attr if isinstance(node, ast.Attribute) else getattr(node, "id", "")
