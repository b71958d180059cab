"""The papers' mission analyses, on top of the models and the master: zero-Doppler passes
and pass design (:mod:`.passes`), frame overlap and Walker constellation sizing
(:mod:`.mission_analysis`), video_sar over a real satellite's pass (:mod:`.stare`), the
reaction wheel payload_sweep needs (:mod:`.sizing`); their commands are in
:mod:`..cli.studies`.  No FMU packs this layer; :mod:`.passes` and :mod:`.mission_analysis`
are plain NumPy on the models."""
