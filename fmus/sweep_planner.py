"""FMU ``SweepPlanner``: maps FMI variables onto :class:`components.sweep_planner.SweepPlanner`."""
from ..components.sweep_planner import SweepPlanner as Model
from .slave import ModelSlave


class SweepPlanner(ModelSlave):
    model_class = Model
