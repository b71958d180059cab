"""FMU ``CmgSteering``: maps FMI variables onto :class:`components.steering.CmgSteering`."""
from ..components.steering import CmgSteering as Model
from .slave import ModelSlave


class CmgSteering(ModelSlave):
    model_class = Model
