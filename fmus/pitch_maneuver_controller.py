"""FMU ``PitchManeuverController``: maps FMI variables onto :class:`components.pitch_maneuver.PitchManeuverController`."""
from ..components.pitch_maneuver import PitchManeuverController as Model
from .slave import ModelSlave


class PitchManeuverController(ModelSlave):
    model_class = Model
