"""Physics and control models in plain NumPy, with no FMI dependency.

Each model is a :class:`model.Model` with its variable table (``VARIABLES``), the single
source of truth from which the FMU wrappers in ``fmus/``, the model descriptions, the
interface docs and the tests are derived.
"""
