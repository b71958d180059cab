"""FMU ``CmgCluster``: maps FMI variables onto :class:`components.cmg_cluster.CmgCluster`."""
from ..components.cmg_cluster import CmgCluster as Model
from .slave import ModelSlave


class CmgCluster(ModelSlave):
    model_class = Model
