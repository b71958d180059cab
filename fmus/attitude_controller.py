"""FMU ``AttitudeController``: maps FMI variables onto :class:`components.attitude_controller.AttitudeController`."""
from ..components.attitude_controller import AttitudeController as Model
from .slave import ModelSlave


class AttitudeController(ModelSlave):
    model_class = Model
