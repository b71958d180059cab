"""What an FMU needs where it runs, said inside it and true of its binaries.

Each FMU's model description and ``documentation/index.html`` name the Python versions,
numpy, the two environment variables a host without Python sets and the Python the FMU was
built for, and the system libraries its binaries need; the binaries are read with
``objdump`` (binutils, beside the C compiler the build needs) to check those."""

import html
import re
import shutil
import subprocess
import sys
import zipfile

import pytest
from fmpy import read_model_description

from agilesat.fmus import FMUS
from agilesat.fmus.build import PYTHONFMU_NEEDS

VERSION = "{}.{}".format(*sys.version_info)


def symbol_versions(binary: bytes, tmp_path) -> set[str]:
    """The symbol versions (GLIBC_2.14, GLIBCXX_3.4.30, ...) a shared library references."""
    objdump = shutil.which("objdump")
    assert objdump, "this test reads the binaries with objdump (binutils)"
    path = tmp_path / "binary.so"
    path.write_bytes(binary)
    listing = subprocess.run([objdump, "-T", str(path)], capture_output=True, text=True)
    assert listing.returncode == 0, listing.stderr
    return set(re.findall(r"\((GLIBC(?:XX)?_[0-9.]+)\)", listing.stdout))


def newest(versions: set[str], family: str) -> str:
    ours = [v for v in versions if v.startswith(family + "_")]
    return max(ours, key=lambda v: tuple(int(x) for x in v.split("_")[1].split(".")))


@pytest.mark.parametrize("name", FMUS)
def test_every_fmu_says_what_it_needs(fmus, name):
    description = read_model_description(str(fmus[name])).description
    with zipfile.ZipFile(fmus[name]) as archive:
        documentation = html.unescape(archive.read("documentation/index.html").decode())
    for text in (description, documentation):
        assert "Python >=3.10 with numpy>=1.24" in text
        assert "AGILESAT_LIBPYTHON" in text and "AGILESAT_PYTHON" in text
        assert f"Python {VERSION}" in text and "of one minor version" in text
        assert "glibc >= 2.32" in text and "GLIBCXX_3.4.30" in text
    assert sys.executable in documentation  # the environment the FMU starts


def test_the_binaries_need_what_the_fmus_say(fmus, tmp_path):
    """The shim needs glibc 2.2.5 at most (its symbols bound to the baseline versions) and
    is NODELETE; pythonfmu's binary needs exactly what PYTHONFMU_NEEDS says."""
    with zipfile.ZipFile(fmus["SatelliteDynamics"]) as archive:
        shim = archive.read("binaries/linux64/SatelliteDynamics.so")
        inner = archive.read("binaries/linux64/pythonfmu-export.so")
    assert {v for v in symbol_versions(shim, tmp_path) if v.startswith("GLIBC_")} == {"GLIBC_2.2.5"}
    (tmp_path / "shim.so").write_bytes(shim)
    dynamic = subprocess.run(
        ["objdump", "-p", str(tmp_path / "shim.so")], capture_output=True, text=True
    ).stdout
    assert re.search(r"FLAGS_1\s+0x[0-9a-f]*[89a-f]\b", dynamic)  # DF_1_NODELETE (0x8)
    needed = symbol_versions(inner, tmp_path)
    assert (newest(needed, "GLIBC"), newest(needed, "GLIBCXX")) == PYTHONFMU_NEEDS
