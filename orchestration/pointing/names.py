"""The names the pointing package's options take: the indices of [Ecss 2008] (§3.2, annex
A), the statistical interpretations, where in its window an index is taken, the display
units of angles.  Plain Python, so that a command line can offer them without loading
NumPy (``agilesat --help``)."""

import math

#: index name: (operation, kind of error it is defined on)
INDICES = {
    "APE": ("absolute", "performance"),
    "MPE": ("mean", "performance"),
    "RPE": ("relative", "performance"),
    "PDE": ("drift", "performance"),
    "PRE": ("drift", "performance"),
    "AKE": ("absolute", "knowledge"),
    "MKE": ("mean", "knowledge"),
    "RKE": ("relative", "knowledge"),
    "KDE": ("drift", "knowledge"),
    "KRE": ("drift", "knowledge"),
}
#: what each index is, in words ([Ecss 2008] §3.2): figure titles
MEANINGS = {
    "APE": "absolute performance error",
    "MPE": "mean performance error",
    "RPE": "relative performance error",
    "PDE": "performance drift error",
    "PRE": "performance reproducibility error",
    "AKE": "absolute knowledge error",
    "MKE": "mean knowledge error",
    "RKE": "relative knowledge error",
    "KDE": "knowledge drift error",
    "KRE": "knowledge reproducibility error",
}
T_IN_WINDOW = ("end", "random")
INTERPRETATIONS = ("temporal", "ensemble", "mixed")
#: display units of angles: rad per unit
ANGLE_UNITS = {
    "rad": 1.0,
    "mrad": 1e-3,
    "urad": 1e-6,
    "µrad": 1e-6,
    "deg": math.pi / 180,
    "arcmin": math.pi / 10_800,
    "arcsec": math.pi / 648_000,
}
