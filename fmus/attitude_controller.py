"""FMU ``AttitudeController``: maps FMI variables onto :class:`components.attitude_control.AttitudeController`."""
from ..components.attitude_control import AttitudeController as Model
from .slave import ModelSlave


class AttitudeController(ModelSlave):
    model_class = Model
