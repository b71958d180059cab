"""The layers point one way: components/ (physics, plain NumPy) imports neither the FMI
wrappers, the FMI libraries nor the orchestration; the scenarios' constants live in
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


#: what the generic master (orchestration/system/, cosim/) may take from outside the
#: orchestration: the cache's root and its checked entries, the switches, the C compiler
#: the FMU build uses
MASTER_MAY_IMPORT = {
    "components.jit",
    "components.cache_files",
    "components.switches",
    "fmus.build",
}


@pytest.mark.parametrize(
    "path",
    sorted((ROOT / "orchestration" / "system").glob("*.py"))
    + sorted((ROOT / "orchestration" / "cosim").glob("*.py")),
    ids=lambda p: f"{p.parent.name}/{p.name}",
)
def test_the_generic_master_knows_no_model(path):
    """Reading, checking and running a system reads what the FMUs' model descriptions say,
    never our model registry (fmus.FMUS, model_class) or the components' variable tables:
    a third-party FMU is treated as ours."""
    bad = [
        f"{path.relative_to(ROOT)}:{line}: imports {module}"
        for line, module in imports(path)
        if module.startswith("...")
        and module.lstrip(".") not in MASTER_MAY_IMPORT
        or module.split(".")[0] == "agilesat"
        and module.split(".")[1] != "orchestration"
    ]
    assert not bad, bad
