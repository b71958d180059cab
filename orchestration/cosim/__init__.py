"""Run a checked system: the run's plan (:mod:`.plan`), the co-simulation master
(:mod:`.master`), its compiled loop (:mod:`.loop`), the loaded FMUs (:mod:`.fmu`),
input/output derivatives (:mod:`.derivatives`) and multi-rate stepping
(:mod:`.multirate`)."""
