"""FMU ``OrbitEnvironment``: maps FMI variables onto :class:`components.orbit.OrbitEnvironment`."""
from ..components.orbit import OrbitEnvironment as Model
from .slave import ModelSlave


class OrbitEnvironment(ModelSlave):
    model_class = Model
