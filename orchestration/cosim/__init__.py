"""Run a checked system: what a run is asked (:mod:`.options`), the run's plan
(:mod:`.plan`), the co-simulation master (:mod:`.master`), its loop (:mod:`.loop`), the
loaded FMUs (:mod:`.fmu`), input/output derivatives (:mod:`.derivatives`) and multi-rate
stepping (:mod:`.multirate`)."""
