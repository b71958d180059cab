"""mkdocs hooks: the pages made from the sources at build time (none of them is committed).

- ``fmus/<Name>.md`` for every FMU of ``agilesat.fmus.FMUS``: its model's docstrings and
  its variable table, rendered by the function that writes ``fmus/INTERFACES.md``
  (``agilesat generate``), and listed in the navigation under "FMUs" and in the
  catalogue of ``fmus/index.md``;
- ``design.md``: the repository's ``DESIGN.md``;
- the API reference: mkdocstrings reads the installed package ``agilesat``, whose
  subpackages are the repository's top-level folders; griffe finds a package only as a
  folder of its name, so one is made of links to them for the build, and
  :class:`Docstrings` shows it the names ``agilesat.orchestration`` imports on first use.

Docstrings are written for Sphinx and Python's help(); :func:`markdown` turns them into
Markdown.
"""

from __future__ import annotations

import importlib
import re
import shutil
import tempfile
from pathlib import Path

import griffe
from mkdocs.plugins import event_priority
from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parent.parent
SUBPACKAGES = ("components", "fmus", "orchestration")
_tree: Path | None = None
_ROLE = re.compile(r":(?:func|class|meth|mod|data|attr|exc|obj):`[~.]*([^`]+)`")


def markdown(docstring: str | None) -> str:
    """A docstring as Markdown: roles become code spans, a literal block's ``::`` a colon
    (the indented block after it is a code block in Markdown too)."""
    text = _ROLE.sub(r"`\1`", (docstring or "").strip())
    return re.sub(r"::$", ":", text, flags=re.M)


class Docstrings(griffe.Extension):
    """Show griffe ``agilesat.orchestration.run`` and the other public names the package
    imports on first use (PEP 562; ``_WHERE`` says from which submodule) as aliases, and
    every docstring as Markdown."""

    def on_module(self, *, mod, **kwargs):
        if mod.path == "agilesat.orchestration":
            from agilesat.orchestration import _WHERE

            for name, where in _WHERE.items():
                mod.set_member(name, griffe.Alias(name, f"{mod.path}.{where}.{name}"))

    def on_object(self, *, obj, **kwargs):
        if obj.docstring is not None:
            obj.docstring.value = markdown(obj.docstring.value)


def fmu_page(name: str) -> str:
    """An FMU's page: what it is (the class and module docstrings) and its variables."""
    from agilesat.fmus import model_class
    from agilesat.fmus.build import interface_rows

    model = model_class(name)
    module = importlib.import_module(model.__module__)
    rows = "".join(
        f"| `{row[0]}` | " + " | ".join(str(c).replace("|", "\\|") for c in row[1:]) + " |\n"
        for row in interface_rows(model)
    )
    return (
        f"# {name}\n\n{markdown(model.__doc__)}\n\n{markdown(module.__doc__)}\n\n"
        "## Variables\n\n"
        "Units are SI (angles in rad); array elements are 1-based FMI structured names "
        "(`w_BI_B[1]`, `inertia[2,3]`).\n\n"
        "| variable | causality | type | unit | start | description |\n"
        f"|---|---|---|---|---|---|\n{rows}"
    )


@event_priority(100)  # before mkdocstrings reads its handlers' paths
def on_config(config):
    global _tree
    if _tree is None:  # once per process (mkdocs serve builds again on every change)
        _tree = Path(tempfile.mkdtemp(prefix="agilesat-api-"))
        (_tree / "agilesat").mkdir()
        for name in SUBPACKAGES:
            (_tree / "agilesat" / name).symlink_to(ROOT / name, target_is_directory=True)
    python = config.plugins["mkdocstrings"].config.handlers.setdefault("python", {})
    python["paths"] = [str(_tree)]

    from agilesat.fmus import FMUS

    for section in config.nav:
        if isinstance(section, dict) and "FMUs" in section:
            section["FMUs"] += [{name: f"fmus/{name}.md"} for name in FMUS]
    return config


def summary(name: str) -> str:
    """The first paragraph of an FMU's model docstring, on one line."""
    from agilesat.fmus import model_class

    return " ".join(markdown(model_class(name).__doc__).split("\n\n")[0].split())


def on_page_markdown(markdown_text, page, **kwargs):
    """The FMU catalogue on fmus/index.md: each FMU's page and its model's summary."""
    if page.file.src_uri != "fmus/index.md":
        return markdown_text
    from agilesat.fmus import FMUS

    rows = "".join(f"| [{name}]({name}.md) | {summary(name)} |\n" for name in FMUS)
    return markdown_text.replace(
        "<!-- fmu catalogue -->", f"| FMU | what it is |\n|---|---|\n{rows}"
    )


def on_files(files, config):
    from agilesat.fmus import FMUS

    for name in FMUS:
        files.append(File.generated(config, f"fmus/{name}.md", content=fmu_page(name)))
    design = (ROOT / "DESIGN.md").read_text(encoding="utf-8")
    # links relative to the repository become links relative to the site
    design = design.replace("(fmus/INTERFACES.md)", "(fmus/index.md)").replace("(docs/", "(")
    files.append(File.generated(config, "design.md", content=design))
    return files


def on_shutdown():
    if _tree is not None:
        shutil.rmtree(_tree, ignore_errors=True)
