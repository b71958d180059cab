"""FMU ``SatelliteDynamics``: maps FMI variables onto :class:`components.satellite_dynamics.SatelliteDynamics`."""
from ..components.satellite_dynamics import SatelliteDynamics as Model
from .slave import ModelSlave


class SatelliteDynamics(ModelSlave):
    model_class = Model
