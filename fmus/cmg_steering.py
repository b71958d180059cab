"""FMU ``CmgSteering``: maps FMI variables onto :class:`components.cmg_steering.CmgSteering`."""
from ..components.cmg_steering import CmgSteering as Model
from .slave import ModelSlave


class CmgSteering(ModelSlave):
    model_class = Model
