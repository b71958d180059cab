"""What a run leaves: the rows recorded as it goes (:mod:`.recorder`), the results
(:mod:`.results`), the summary (:mod:`.summary`), figures (:mod:`.plots`,
:mod:`.figure_layout`), progress (:mod:`.progress`), the assertions (:mod:`.checks`) and
the pytest plugin (:mod:`.pytest_plugin`)."""
