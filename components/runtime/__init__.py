"""The runtime floor: the machine room under the models, the FMU layer and the master.

Nothing here knows a model, an FMU or a system: it imports nothing of agilesat outside this
package (tests/test_layers.py), and everything above may import it.

- :mod:`.jit` — the models' kernels compiled by numba once a run is long, the kernel
  convention, the compile cache keyed on content;
- :mod:`.flat` — the flat arrays kernels work on: offsets by name (the variable table's
  and a kernel's :func:`~.flat.state_table`), small accessors, and compilable bit-exact
  twins of CPython functions numba computes otherwise;
- :mod:`.cache` — agilesat's cache directory and its entries sealed with their SHA-256;
- :mod:`.switches` — every ``AGILESAT_*`` environment variable, read and checked;
- :mod:`.toolchain` — the C compiler and files written atomically.
- :mod:`.choices` — named choices: how a description lists them, and their one parser.
"""
