"""One operating point or one load: time histories and their response measures, linear stability
and Hopf points, device curves, calibration, and the executors that spread independent units of
work. Imports no other family of the analyses."""
