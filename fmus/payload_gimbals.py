"""FMU ``PayloadGimbals``: maps FMI variables onto :class:`components.payload_gimbals.PayloadGimbals`."""
from ..components.payload_gimbals import PayloadGimbals as Model
from .slave import ModelSlave


class PayloadGimbals(ModelSlave):
    model_class = Model
