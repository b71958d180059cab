"""Mission analysis on top of the models (plain NumPy, no FMI): zero-Doppler passes and
pass design (:mod:`.passes`), frame overlap and Walker constellation sizing
(:mod:`.mission`).  No FMU packs this layer; it imports the models, never the reverse."""
