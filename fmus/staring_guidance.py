"""FMU ``StaringGuidance``: maps FMI variables onto :class:`components.staring.StaringGuidance`."""
from ..components.staring import StaringGuidance as Model
from .slave import ModelSlave


class StaringGuidance(ModelSlave):
    model_class = Model
