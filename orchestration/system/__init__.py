"""Read and check a system: SSP files (:mod:`.ssp`), the checks against the FMUs' model
descriptions (:mod:`.validation`, :mod:`.agreement`), the evaluation order
(:mod:`.schedule`), parameter values (:mod:`.parameters`) and units (:mod:`.units`).
Nothing here loads an FMU's binary."""
