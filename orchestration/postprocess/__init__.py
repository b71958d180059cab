"""What runs and campaigns left, read back: a run's directory (:mod:`.run_directory`), the
interactive report of a run or a campaign (:mod:`.report`), the ECSS pointing indices of
recorded runs and campaigns (:mod:`.recorded`), a run's CCSDS ephemerides
(:mod:`.ephemeris`) and the assertions on results (:mod:`.checks`).  Their commands are
in :mod:`..cli`."""
