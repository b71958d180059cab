"""FMU ``OrbitEnvironment``: maps FMI variables onto :class:`components.orbit_environment.OrbitEnvironment`."""
from ..components.orbit_environment import OrbitEnvironment as Model
from .slave import ModelSlave


class OrbitEnvironment(ModelSlave):
    model_class = Model
