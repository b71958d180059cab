"""Reading SSP 1.0 system files (orchestration/system/ssp.py) without loading any FMU: parameter
bindings inline, from an .ssv file with a prefix, at system level; the default experiment
and our master's annotation; errors that name the file and line."""

import pytest

from agilesat.orchestration.system.ssp import SystemFileError, read_system

HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"'
    ' xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"'
    ' xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"'
    ' version="1.0" name="toy">\n'
)
SSV = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"'
    ' version="1.0" name="set">\n'
    "<ssv:Parameters>\n"
    '<ssv:Parameter name="gain"><ssv:Real value="2.5"/></ssv:Parameter>\n'
    '<ssv:Parameter name="count"><ssv:Integer value="3"/></ssv:Parameter>\n'
    "</ssv:Parameters>\n"
    "</ssv:ParameterSet>\n"
)


def inline(*parameters):
    return (
        '<ssd:ParameterValues><ssv:ParameterSet version="1.0" name="set"><ssv:Parameters>'
        + "".join(parameters)
        + "</ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues>"
    )


def system(tmp_path, component_binding, system_binding="", experiment=""):
    (tmp_path / "A.fmu").write_bytes(b"")  # only its existence is checked when reading
    (tmp_path / "set.ssv").write_text(SSV)
    system_bindings = f"<ssd:ParameterBindings>{system_binding}</ssd:ParameterBindings>"
    text = (
        HEAD
        + '<ssd:System name="toy">'
        + (system_bindings if system_binding else "")  # the schema puts them first
        + "<ssd:Elements>"
        + '<ssd:Component name="A" source="A.fmu" type="application/x-fmu-sharedlibrary">'
        + f"<ssd:ParameterBindings>{component_binding}</ssd:ParameterBindings>"
        + "</ssd:Component></ssd:Elements></ssd:System>"
        + experiment
        + "</ssd:SystemStructureDescription>\n"
    )
    path = tmp_path / "toy.ssd"
    path.write_text(text)
    return path


def test_an_ssv_file_with_a_prefix_inline_values_and_system_level_values(tmp_path):
    path = system(
        tmp_path,
        '<ssd:ParameterBinding source="set.ssv" prefix="ctrl."/>',
        "<ssd:ParameterBinding>"
        + inline('<ssv:Parameter name="A.on"><ssv:Boolean value="true"/></ssv:Parameter>')
        + "</ssd:ParameterBinding>",
        '<ssd:DefaultExperiment startTime="1.0" stopTime="5.0"><ssd:Annotations>'
        '<ssc:Annotation type="org.agilesat.master"><m:Master xmlns:m="http://agilesat.org/ssp/master"'
        ' stepSize="0.25" algorithm="jacobi"/></ssc:Annotation></ssd:Annotations>'
        "</ssd:DefaultExperiment>",
    )
    read = read_system(path)
    values = {(p.component, p.name): (p.type, p.value) for p in read.parameters}
    assert values == {
        ("A", "ctrl.gain"): ("Real", 2.5),
        ("A", "ctrl.count"): ("Integer", 3),
        ("A", "on"): ("Boolean", True),
    }
    origins = {p.name: p.origin for p in read.parameters}
    assert origins["ctrl.gain"] == f"{tmp_path / 'set.ssv'}:4"  # line 4 of SSV
    assert origins["on"].startswith(f"{path}:")
    assert (read.start_time, read.stop_time, read.step_size, read.algorithm) == (
        1.0,
        5.0,
        0.25,
        "jacobi",
    )
    assert [c.name for c in read.components] == ["A"]


@pytest.mark.parametrize(
    "component_binding, system_binding, message",
    [
        ('<ssd:ParameterBinding source="none.ssv"/>', "", "binding source 'none.ssv' not found"),
        ('<ssd:ParameterBinding source="../out.ssv"/>', "", "resolves outside the package"),
        ("<ssd:ParameterBinding/>", "", "without source or inline ssv:ParameterSet"),
        (
            '<ssd:ParameterBinding source="set.ssv"/>',
            "<ssd:ParameterBinding>"
            + inline('<ssv:Parameter name="on"><ssv:Boolean value="true"/></ssv:Parameter>')
            + "</ssd:ParameterBinding>",
            "system-level parameter 'on' must be 'Component.variable'",
        ),
        (
            "<ssd:ParameterBinding>"
            + inline('<ssv:Parameter name="g"><ssv:Real value="inf"/></ssv:Parameter>')
            + "</ssd:ParameterBinding>",
            "",
            "bad Real value 'inf': not finite",
        ),
        (
            "<ssd:ParameterBinding>"
            + inline('<ssv:Parameter name="n"><ssv:Integer value="4294967296"/></ssv:Parameter>')
            + "</ssd:ParameterBinding>",
            "",
            r"bad Integer value '4294967296': an Integer is from -2147483648 to 2147483647",
        ),
    ],
)
def test_a_bad_binding_names_the_file_and_what_is_wrong(
    tmp_path, component_binding, system_binding, message
):
    path = system(tmp_path, component_binding, system_binding)
    if "../out.ssv" in component_binding:  # only a package refuses a source outside it
        import zipfile

        package = tmp_path / "toy.ssp"
        with zipfile.ZipFile(package, "w") as archive:
            archive.write(path, "SystemStructure.ssd")
            archive.write(tmp_path / "A.fmu", "A.fmu")
        path = package
    with pytest.raises(SystemFileError, match=message):
        read_system(path)


def test_a_parameter_bound_twice_in_one_set_is_refused_naming_both_lines(tmp_path):
    path = system(
        tmp_path,
        "<ssd:ParameterBinding>"
        + inline(
            '<ssv:Parameter name="g">\n<ssv:Real value="1"/></ssv:Parameter>\n'
            '<ssv:Parameter name="g">\n<ssv:Real value="2"/></ssv:Parameter>'
        )
        + "</ssd:ParameterBinding>",
    )
    with pytest.raises(
        SystemFileError,
        match=rf"{path}:\d+: parameter 'g' is bound twice in one parameter set \(first at "
        r"line \d+\)",
    ):
        read_system(path)


def test_a_step_size_that_is_not_a_number_names_file_and_line(tmp_path):
    path = system(
        tmp_path,
        '<ssd:ParameterBinding source="set.ssv"/>',
        experiment='<ssd:DefaultExperiment><ssd:Annotations><ssc:Annotation type="org.agilesat.'
        'master">\n<m:Master xmlns:m="http://agilesat.org/ssp/master" stepSize="abc"/>'
        "</ssc:Annotation></ssd:Annotations></ssd:DefaultExperiment>",
    )
    with pytest.raises(
        SystemFileError,
        match=rf"{path}:\d+: the org.agilesat.master annotation's stepSize is 'abc'",
    ):
        read_system(path)


def test_the_package_bound_counts_what_its_fmus_unpack_to(tmp_path):
    """A 2 MiB member of an FMU inside the package (a few kB packed) passes a 1 MiB limit
    on the package's own members, not on what the FMU unpacks to when it runs."""
    import zipfile

    system(tmp_path, '<ssd:ParameterBinding source="set.ssv"/>')
    with zipfile.ZipFile(tmp_path / "A.fmu", "w", zipfile.ZIP_DEFLATED) as fmu:
        fmu.writestr("resources/zeros", bytes(2 << 20))
    package = tmp_path / "toy.ssp"
    with zipfile.ZipFile(package, "w") as archive:
        for name in ("toy.ssd", "A.fmu", "set.ssv"):
            archive.write(tmp_path / name, "SystemStructure.ssd" if name == "toy.ssd" else name)
    assert read_system(package, max_unpacked=4 << 20).components[0].name == "A"
    with pytest.raises(
        SystemFileError, match=r"with its FMUs, to more than the limit of 1048576 bytes \(A.fmu"
    ):
        read_system(package, max_unpacked=1 << 20)


@pytest.mark.parametrize(
    "extra", [10_000, pytest.param(70_000, marks=pytest.mark.slow, id="zip64")]
)
def test_a_package_of_more_members_than_it_may_have_is_refused_before_reading_them(tmp_path, extra):
    """Counted from the zip's end record (zip64's beyond 65,535), before zipfile reads its
    directory: an object per member, a gigabyte for a million empty ones."""
    import zipfile

    package = tmp_path / "p.ssp"
    with zipfile.ZipFile(package, "w") as archive:
        archive.writestr("SystemStructure.ssd", "x")
        for k in range(extra):
            archive.writestr(f"e/{k}", b"")
    with pytest.raises(SystemFileError, match=rf"a zip archive of {extra + 1} members, more"):
        read_system(package)
