"""FMU ``SweepPlanner``: maps FMI variables onto :class:`components.sweep.SweepPlanner`."""
from ..components.sweep import SweepPlanner as Model
from .slave import ModelSlave


class SweepPlanner(ModelSlave):
    model_class = Model
