"""The papers' mission analyses, on top of the models and the master: zero-Doppler passes
and pass design (:mod:`.passes`), frame overlap and Walker constellation sizing
(:mod:`.mission`), video_sar over a real satellite's pass (:mod:`.stare`), the reaction
wheel payload_sweep needs (:mod:`.sizing`), and their commands (:mod:`.cli`).  No FMU
packs this layer; :mod:`.passes` and :mod:`.mission` are plain NumPy on the models."""
