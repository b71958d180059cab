"""The layers point one way: the runtime (components/runtime/) under the physics
(components/, plain NumPy) under the FMU layer (fmus/) under the orchestration; the physics
imports neither the FMI libraries nor anything above it; the scenarios' constants live in
orchestration/scenarios/; the generic master (orchestration/system/, cosim/) knows no model
of ours."""

import ast

import pytest

from helpers import ROOT

FORBIDDEN = ("orchestration", "fmus", "pythonfmu", "fmpy")


def imports(path):
    """(line, module) of every import in a file; relative ones as written (..orchestration)."""
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            yield from ((node.lineno, alias.name) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            yield node.lineno, "." * node.level + (node.module or "")


@pytest.mark.parametrize("path", sorted((ROOT / "components").rglob("*.py")), ids=lambda p: p.name)
def test_components_import_no_fmi_and_no_orchestration(path):
    bad = [
        f"{path.relative_to(ROOT)}:{line}: imports {module}"
        for line, module in imports(path)
        if any(part in FORBIDDEN for part in module.lstrip(".").split(".")[:2])
        or module.split(".")[0] == "agilesat"
        and module.split(".")[1] in FORBIDDEN
    ]
    assert not bad, bad


def test_no_scenario_constant_is_defined_in_components():
    defined = [
        f"{path.relative_to(ROOT)}: {target.id}"
        for path in (ROOT / "components").rglob("*.py")
        for node in ast.parse(path.read_text()).body
        if isinstance(node, ast.Assign)
        for target in node.targets
        if isinstance(target, ast.Name)
        and target.id.startswith(("VIDEO_SAR_", "SCAN_PITCH_", "PAYLOAD_SWEEP_", "PAPER_"))
    ]
    assert not defined, defined


#: the layers, lowest first: each module imports only from its own layer and those below
#: (the runtime: jit, flat arrays, the cache, switches, the C toolchain; the physics; the
#: FMU layer; the orchestration)
LAYERS = ("components/runtime", "components", "fmus", "orchestration")
#: imports that point up, each with its reason (none)
UPWARD_ALLOWED: dict[tuple[str, str], str] = {}
SOURCES = sorted(
    path
    for layer in ("components", "fmus", "orchestration")
    for path in (ROOT / layer).rglob("*.py")
    if "build" not in path.relative_to(ROOT).parts
)


def layer(relative: str) -> int | None:
    """The layer of a module or package given as a path ('fmus/build.py', 'components'),
    None outside the package (pythonfmu, numpy, ...)."""
    for rank, prefix in enumerate(LAYERS):
        if relative == prefix or relative.startswith(prefix + "/"):
            return rank
    return None


def target(path, module: str) -> str:
    """The package path an import names ('..components.runtime.jit' from fmus/x.py ->
    'components/runtime/jit'), '' for a module outside agilesat."""
    if module.startswith("."):
        level = len(module) - len(module.lstrip("."))
        package = path.relative_to(ROOT).parent.parts
        base = package[: len(package) - level + 1]
        return "/".join([*base, *filter(None, module.lstrip(".").split("."))])
    parts = module.split(".")
    return "/".join(parts[1:]) if parts[0] == "agilesat" else ""


def test_no_import_points_up():
    """components/runtime/ < components/ < fmus/ < orchestration/: the runtime knows no
    model, the models no FMU, the FMU layer no master."""
    bad = [
        f"{relative}:{line}: imports {module}"
        for path in SOURCES
        for line, module in imports(path)
        if (relative := path.relative_to(ROOT).as_posix())
        and (to := target(path, module))
        and layer(to) > layer(relative)
        and (relative, to) not in UPWARD_ALLOWED
    ]
    assert not bad, bad


@pytest.mark.parametrize(
    "path",
    sorted((ROOT / "orchestration" / "system").glob("*.py"))
    + sorted((ROOT / "orchestration" / "cosim").glob("*.py")),
    ids=lambda p: f"{p.parent.name}/{p.name}",
)
def test_the_generic_master_knows_no_model(path):
    """Reading, checking and running a system reads what the FMUs' model descriptions say,
    never our model registry (fmus.FMUS, model_class) or the components' variable tables:
    a third-party FMU is treated as ours.  Below the orchestration it uses the runtime
    alone (the cache, the switches, the C compiler)."""
    bad = [
        f"{path.relative_to(ROOT)}:{line}: imports {module}"
        for line, module in imports(path)
        if (to := target(path, module))
        and layer(to) != LAYERS.index("orchestration")
        and layer(to) != LAYERS.index("components/runtime")
    ]
    assert not bad, bad


#: orchestration/'s own layers, lowest first (docs/architecture.md): reading and checking
#: a system; the pointing indices; what a run leaves; running it; a mission in Python, the
#: shipped scenarios on it; what runs left read back (report, indices, ephemerides,
#: assertions); a target run, exported (with its coupling error) or described end to end,
#: a run's numerical error; campaigns; the papers' studies; the command line.  A module
#: imports from its own layer and those below it only.
ORCHESTRATION = (
    ("system", "provenance.py"),
    ("pointing",),
    ("output",),
    ("cosim",),
    ("mission",),
    ("scenarios",),
    ("postprocess",),
    ("runner.py", "export.py", "info.py", "coupling_error.py", "error_estimate.py"),
    ("campaign",),
    ("studies",),
    ("cli", "__main__.py", "__init__.py"),
)
#: the imports inside orchestration/ that point up, each with its reason
ORCHESTRATION_UPWARD = {
    ("output/pytest_plugin.py", "runner.py"): "the pytest plugin's fixture runs a target; "
    "the plugin's entry point (pytest11, pyproject.toml) names this module",
    ("output/pytest_plugin.py", "postprocess"): "the plugin re-exports the assertions",
}


def _orchestration_rank(relative: str) -> int:
    """The layer of a path under orchestration/ ('cosim/plan.py', 'runner.py')."""
    first = relative.split("/")[0]
    for rank, members in enumerate(ORCHESTRATION):
        if first in members:
            return rank
    raise AssertionError(f"orchestration/{relative} is in no layer of ORCHESTRATION")


def _orchestration_imports(path):
    """(line, path under orchestration/ of the module imported) of every relative import
    of ``path`` into orchestration/."""
    package = path.relative_to(ROOT / "orchestration").parent.parts
    for line, module in imports(path):
        level = len(module) - len(module.lstrip("."))
        if not level or level > len(package) + 1:
            continue  # absolute, or above orchestration/ (components, fmus)
        parts = [*package[: len(package) - level + 1], *filter(None, module[level:].split("."))]
        if not parts:
            continue  # the package itself (its lazy names)
        folder = ROOT / "orchestration" / parts[0]
        yield line, parts[0] if folder.is_dir() else f"{parts[0]}.py"


def test_orchestration_imports_point_down():
    """No module of orchestration/ imports from a layer above its own, outside
    ORCHESTRATION_UPWARD (and each of those is still there)."""
    up, used = [], set()
    for path in sorted((ROOT / "orchestration").rglob("*.py")):
        relative = path.relative_to(ROOT / "orchestration").as_posix()
        rank = _orchestration_rank(relative)
        for line, target in _orchestration_imports(path):
            if _orchestration_rank(target) <= rank:
                continue
            if (relative, target) in ORCHESTRATION_UPWARD:
                used.add((relative, target))
            else:
                up.append(f"orchestration/{relative}:{line}: imports {target}, a layer above")
    assert not up, up
    assert used == set(ORCHESTRATION_UPWARD)
