"""Read and check a system: SSP files (:mod:`.ssp`, a component's own step :mod:`.steps`),
what the FMUs' model descriptions say
(:mod:`.description`), the checks against them (:mod:`.validation`, :mod:`.agreement`),
the evaluation order (:mod:`.schedule`), parameter values (:mod:`.parameters`) and units
(:mod:`.units`).  Nothing here loads an FMU's binary."""
