"""FMU ``Flywheel``: maps FMI variables onto :class:`components.flywheel.Flywheel`."""
from ..components.flywheel import Flywheel as Model
from .slave import ModelSlave


class Flywheel(ModelSlave):
    model_class = Model
