"""Analyses of the gear model, in families that import one another only downward
(tests/test_layers.py):

* :mod:`.core`: time histories and response measures, linear stability and Hopf points, device
  curves, calibration, executors;
* :mod:`.diagrams`: bifurcation diagrams, Hopf curves, curves of cycles (imports core);
* :mod:`.maps`: stability maps and design figures of merit (core, diagrams);
* :mod:`.ground`: ground runs (core, diagrams);
* :mod:`.decisions`: design space, sensitivities, optimiser, robustness, studies (all of the above).

Built on :mod:`shimmy.model` and the generic engine :mod:`shimmy.continuation`; never imports
the service layer or a UI.
"""
