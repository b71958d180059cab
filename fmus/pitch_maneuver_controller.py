"""FMU ``PitchManeuverController``: maps FMI variables onto :class:`components.pitch_maneuver_controller.PitchManeuverController`."""
from ..components.pitch_maneuver_controller import PitchManeuverController as Model
from .slave import ModelSlave


class PitchManeuverController(ModelSlave):
    model_class = Model
