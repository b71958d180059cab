"""FMU ``PayloadGimbals``: maps FMI variables onto :class:`components.payload.PayloadGimbals`."""
from ..components.payload import PayloadGimbals as Model
from .slave import ModelSlave


class PayloadGimbals(ModelSlave):
    model_class = Model
