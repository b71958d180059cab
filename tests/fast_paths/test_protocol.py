"""The slave and the shim share one protocol table (fmus/protocol.py): the C header the shim
compiles against is generated from it, a stale one is refused by `agilesat generate
--check` and by the build, and no constant of it is written anywhere else."""

import re

import pytest

from agilesat.fmus import build, protocol
from agilesat.orchestration import cli
from helpers import ROOT

NAMES = [name for _, names in protocol.SECTIONS for name in names]


def test_the_header_is_generated_from_the_table():
    header = build.PROTOCOL_HEADER.read_text()
    assert header == protocol.header()
    for name in NAMES:
        value = getattr(protocol, name)
        assert re.search(rf"^#define {name} {re.escape(repr(value))}u?$", header, re.M) or (
            re.search(rf"^#define {name} {value}u?$", header, re.M)
        ), name


@pytest.fixture
def stale(tmp_path, monkeypatch):
    """The protocol header as if the table had changed since it was generated."""
    path = tmp_path / "protocol.h"
    path.write_text(protocol.header().replace("#define N_BLOCK", "#define N_BLOCK 1 +"))
    monkeypatch.setattr(build, "PROTOCOL_HEADER", path)
    return path


def test_generate_check_fails_on_a_stale_header_and_generate_rewrites_it(stale, capsys):
    assert cli.main(["generate", "--check"]) == 1
    assert str(stale) in capsys.readouterr().err
    assert stale.read_text() != protocol.header()
    generated = build.generated_files()[stale]()
    stale.write_bytes(generated)
    assert cli.main(["generate", "--check"]) == 0


def test_the_build_refuses_a_stale_header(stale, tmp_path):
    with pytest.raises(
        build.BuildError, match=r"protocol.h is out of date: run `agilesat generate`"
    ):
        build._shim_library(tmp_path)


def test_no_protocol_constant_is_written_twice():
    """Only the table defines them: no #define, enum or assignment of one elsewhere in the
    shim or the slave's modules."""
    sources = [
        *(ROOT / "fmus" / "shim").glob("*.[ch]"),
        *(ROOT / "fmus").glob("*.py"),
        *(ROOT / "components").glob("*.py"),
    ]
    names = "|".join(NAMES)
    defined = re.compile(
        rf"^\s*#define\s+({names})\b|^[\w\s,]*\b({names})\b[\w\s,]*=[^=]|"
        rf"enum\s*\{{[^}}]*\b({names})\b",
        re.M,
    )
    found = [
        f"{path.relative_to(ROOT)}: {match.group(0)!r}"
        for path in sources
        if path not in (build.PROTOCOL_HEADER, ROOT / "fmus" / "protocol.py")
        for match in defined.finditer(path.read_text())
    ]
    assert found == []
