"""FMU ``StaringGuidance``: maps FMI variables onto :class:`components.staring_guidance.StaringGuidance`."""
from ..components.staring_guidance import StaringGuidance as Model
from .slave import ModelSlave


class StaringGuidance(ModelSlave):
    model_class = Model
