"""FMU ``SatelliteDynamics``: maps FMI variables onto :class:`components.rigid_body.SatelliteDynamics`."""
from ..components.rigid_body import SatelliteDynamics as Model
from .slave import ModelSlave


class SatelliteDynamics(ModelSlave):
    model_class = Model
