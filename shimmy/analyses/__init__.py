"""Analyses of the gear model: time histories and response measures, linear stability and
Hopf points, bifurcation diagrams, Hopf curves, stability maps, design metrics, parametric
studies, calibration, device curves, and the executors that spread independent units of work.

Built on :mod:`shimmy.model` and the generic engine :mod:`shimmy.continuation`; never imports
the service layer or a UI.
"""
