"""FMU ``CmgCluster``: maps FMI variables onto :class:`components.cmg.CmgCluster`."""
from ..components.cmg import CmgCluster as Model
from .slave import ModelSlave


class CmgCluster(ModelSlave):
    model_class = Model
