"""Analyses of the gear model, in families that import one another only downward
(tests/test_layers.py):

* ``core``: time histories and response measures, linear stability and Hopf points, device
  curves, calibration, executors;
* ``diagrams``: bifurcation diagrams, Hopf curves, curves of cycles (imports core);
* ``maps``: stability maps and design figures of merit (core, diagrams);
* ``ground``: ground runs (core, diagrams);
* ``decisions``: design space, sensitivities, optimiser, robustness, studies (all of the above).

Built on :mod:`shimmy.model` and the generic engine :mod:`shimmy.continuation`; never imports
the service layer or a UI.
"""
