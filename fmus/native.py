"""A model's C entries compiled ahead of time, into the FMU: compiled from the first call.

The C entries (``c_entries.py``) are numba cfuncs, compiled in the process that runs them:
importing numba and loading even cached machine code costs about 0.7 s per process, so a
short run kept its kernels' Python and a long one switched tier in its middle.  Here
``agilesat build`` takes each entry's final LLVM module (numba's own optimised IR, the
machine code the JIT would make of it), makes every function but the entries internal,
and has LLVM emit it as position-independent code for the architecture's baseline CPU (no
host-specific instructions: the FMU runs on any machine of its platform; no fast-math
flags are in the IR, so the arithmetic is the same IEEE operations in the same order as
the JIT's and the kernels' Python, bit for bit: tests/fast_paths/test_native.py).  The C
compiler links it into ``binaries/<platform>/agilesat_kernels.so`` with a manifest
``agilesat_kernels.json`` beside it.

The link table.  The code calls numba's runtime (``NRT_*``, memory of temporary arrays)
and helper library (``numba_*``), which no library exports for a linker to name: each is
a one-jump trampoline through a table of addresses (``agilesat_links()`` returns it),
which the loader fills from numba's two runtime extensions (their ``c_helpers``, what
numba hands its JIT; the extensions are loaded as files, numba itself is not imported).
The Python C API (``Py*``, the error path of a raise) is left to the dynamic linker, as
for any extension module; the C and math libraries are linked.  The manifest records
numba's version and the content key of each model's code (the compile cache's): with
another numba installed, code edited since the build, or a library whose SHA-256 does not
match, the entries are compiled in the process as before (c_entries.py), with a warning.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import hashlib
import importlib.machinery
import importlib.util
import json
import platform
import subprocess
import sys
import tempfile
import warnings
from importlib import metadata
from pathlib import Path

from ..components.runtime import jit
from ..components.runtime.switches import value

LIBRARY, MANIFEST = "agilesat_kernels.so", "agilesat_kernels.json"
#: the prefixes of the symbols the link table resolves (module docstring), and the Python
#: C API's, which the dynamic linker resolves
LINKED, PYTHON = ("NRT_", "numba_"), ("Py", "_Py")
#: a trampoline and the table's accessor per architecture (GNU assembler; ``offset``: the
#: symbol's slot): x86-64 only so far, elsewhere numba compiles the entries in the process
_JUMPS = {
    "x86_64": (
        "{name}:\n\tjmp *.Llinks+{offset}(%rip)\n",
        "agilesat_links:\n\tleaq .Llinks(%rip), %rax\n\tret\n",
    ),
}


# -- at build time (numba and llvmlite) ---------------------------------------------------
def build(models, folder: Path, compiler: str) -> dict[str, bytes]:
    """The library and manifest of the C entries of ``models`` (their kernels compiled by
    numba in this process), as FMU entries ``{arcname-in-binaries: bytes}``; {} where
    there is nothing to compile."""
    import llvmlite.binding as llvm

    from . import c_entries

    jumps = _JUMPS.get(platform.machine())
    if jumps is None:
        raise RuntimeError(f"no trampolines for the architecture {platform.machine()}")
    numba = jit._numba()
    llvm.initialize_native_target()
    llvm.initialize_native_asmprinter()
    module, names, sources = None, {}, {}
    for model in models:
        for entry in c_entries.of(model)[:2]:
            if entry is None:
                continue
            # compiled here, without the cache (what a cache loads keeps no IR), first in
            # the process: numba numbers the functions alike in every build
            fresh = numba.njit(entry.kernel.py_func)
            cfunc = c_entries.cfunc(entry.kernel, entry.role, fresh, cache=False)
            part = llvm.parse_assembly(str(cfunc._library._final_module))
            if not _complete(part, cfunc.native_name):
                raise RuntimeError(f"numba's module of {cfunc.native_name} is not complete")
            for symbol in (*part.functions, *part.global_variables):
                if not symbol.is_declaration and symbol.name != cfunc.native_name:
                    symbol.linkage = "internal"
            # named by model and role, not by numba's per-process counters: the same
            # sources make the same library
            name = f"agilesat_{model.__qualname__}_{entry.role}"
            part.get_function(cfunc.native_name).name = name
            names.setdefault(model.__qualname__, {})[entry.role] = name
            sources[model.__qualname__] = _source_key(model)
            if module is None:
                module = part
            else:
                module.link_in(part)
    if module is None:
        return {}
    declared = {s.name for s in (*module.functions, *module.global_variables)
                if s.is_declaration and not s.name.startswith("llvm.")}  # fmt: skip
    links = sorted(n for n in declared if n.startswith(LINKED))  # every part _complete
    target = llvm.Target.from_triple(module.triple)  # cpu "": the architecture's baseline
    machine = target.create_target_machine(opt=3, reloc="pic", codemodel="default")
    (folder / "kernels.o").write_bytes(machine.emit_object(module))
    jump, table = jumps
    assembly = "\t.text\n" + "".join(
        f"\t.globl {name}\n\t.hidden {name}\n\t.type {name}, @function\n"
        + jump.format(name=name, offset=8 * i)
        for i, name in enumerate(links)
    )
    assembly += f"\t.globl agilesat_links\n{table}\t.bss\n\t.p2align 3\n.Llinks:\n"
    assembly += f'\t.zero {8 * max(len(links), 1)}\n\t.section .note.GNU-stack,"",@progbits\n'
    (folder / "links.s").write_text(assembly)
    library = folder / LIBRARY
    subprocess.run(
        [compiler, "-shared", "-s", "-o", str(library), str(folder / "kernels.o"),
         str(folder / "links.s"), "-lm", "-Wl,-Bsymbolic"],
        check=True, capture_output=True, text=True,
    )  # fmt: skip
    data = library.read_bytes()
    manifest = {
        "numba": metadata.version("numba"),
        "machine": platform.machine(),
        "sha256": hashlib.sha256(data).hexdigest(),
        "models": names,
        "sources": sources,
        "links": links,
    }
    return {LIBRARY: data, MANIFEST: json.dumps(manifest, indent=1, sort_keys=True).encode()}


def _complete(module, entry: str) -> bool:
    """Does ``module`` define the function ``entry`` and everything it calls but what is
    found outside the library (:func:`_external`)?"""
    defined = any(f.name == entry and not f.is_declaration for f in module.functions)
    return defined and all(_external(f.name) for f in module.functions if f.is_declaration)


# -- at load time (no numba import) -------------------------------------------------------
def entries(model_class) -> dict[str, int]:
    """``{role: address}`` of the ahead-of-time C entries of ``model_class`` inside the FMU
    its code was loaded from; {} outside an FMU, with AGILESAT_NATIVE=0 or AGILESAT_JIT=0,
    or (with a warning) where the FMU's library cannot be used here."""
    if not (value("AGILESAT_NATIVE") and value("AGILESAT_JIT")):
        return {}
    source = Path(sys.modules[model_class.__module__].__file__ or "")
    folder = source.resolve().parents[3] / "binaries" if len(source.parents) > 3 else None
    found = list(folder.glob(f"*/{MANIFEST}")) if folder and folder.is_dir() else []
    if not found:
        return {}
    try:
        library, manifest = _load(found[0].parent)
        names = manifest["models"].get(model_class.__qualname__, {})
        if names and manifest["sources"][model_class.__qualname__] != _source_key(model_class):
            raise ValueError("the FMU's code is not the code it was built from")
        return {role: ctypes.cast(getattr(library, name), ctypes.c_void_p).value
                for role, name in names.items()}  # fmt: skip
    except (OSError, ValueError, KeyError, AttributeError, TypeError) as exc:
        warnings.warn(
            f"agilesat: {found[0].parent / LIBRARY} is not used ({exc}): "
            f"{model_class.__qualname__}'s kernels are compiled in this process",
            stacklevel=2,
        )
        return {}


def _source_key(model_class) -> str:
    """The content key of the model's code and everything its kernels may call (the
    compile cache's, components/runtime/jit.py)."""
    module = model_class.__module__
    return jit.content_key(module, sys.modules[module].__file__)


@functools.cache
def _load(folder: Path):
    """The FMU's library, its link table filled, and its manifest (once per FMU folder)."""
    manifest = json.loads((folder / MANIFEST).read_text())
    installed = metadata.version("numba")
    if manifest["numba"] != installed or manifest["machine"] != platform.machine():
        raise ValueError(
            f"built with numba {manifest['numba']} on {manifest['machine']}, "
            f"this is numba {installed} on {platform.machine()}"
        )
    path = folder / LIBRARY
    if hashlib.sha256(path.read_bytes()).hexdigest() != manifest["sha256"]:
        raise ValueError("it does not match the SHA-256 of its manifest")
    library = ctypes.CDLL(str(path))
    library.agilesat_links.restype = ctypes.POINTER(ctypes.c_void_p)
    table = library.agilesat_links()
    for slot, name in enumerate(manifest["links"]):
        table[slot] = _address(name)
    return library, manifest


def _address(name: str) -> int:
    """The address of a linked symbol (module docstring, "The link table")."""
    if name.startswith("NRT_"):
        return _numba_extension("core/runtime/_nrt_python").c_helpers[name[4:]]
    return _numba_extension("_helperlib").c_helpers[name[6:]]  # numba_*


@functools.cache
def _external(name: str) -> bool:
    """Is ``name`` found outside the library: an LLVM intrinsic, the link table's (numba's
    runtime), or the dynamic linker's where the library is loaded (the Python C API, in
    every process that runs our slave, as for any extension module; the C and math
    libraries)?"""
    if name.startswith(("llvm.", *LINKED, *PYTHON)):
        return True
    libm = ctypes.CDLL(ctypes.util.find_library("m"))
    return hasattr(ctypes.CDLL(None), name) or hasattr(libm, name)


@functools.cache
def _numba_extension(relative: str):
    """One of numba's runtime extensions: numba's own where numba is imported, else the
    extension file loaded alone (its initialisation imports numpy, not numba)."""
    dotted = "numba." + relative.replace("/", ".")
    if dotted in sys.modules:
        return sys.modules[dotted]
    spec = importlib.util.find_spec("numba")
    if spec is None or not spec.submodule_search_locations:
        raise ValueError("numba is not installed (its runtime library is needed)")
    base = Path(spec.submodule_search_locations[0]) / relative
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        if base.with_name(base.name + suffix).is_file():
            loader = importlib.machinery.ExtensionFileLoader(
                base.name, str(base.with_name(base.name + suffix))
            )
            module = importlib.util.module_from_spec(
                importlib.util.spec_from_loader(base.name, loader)
            )
            loader.exec_module(module)
            return module
    raise ValueError(f"numba's {relative} extension is missing")


def build_in(models, compiler: str) -> dict[str, bytes]:
    """:func:`build` in a temporary folder."""
    with tempfile.TemporaryDirectory() as folder:
        return build(models, Path(folder), compiler)
