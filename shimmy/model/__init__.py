"""The gear model: parameters, configurations, the NES and the particle damper, the equations
with their analytic Jacobians, a plain reference transcription and the compiled integrator kernel.

Imports only :mod:`shimmy.errors` beside itself; nothing here runs an analysis.
"""
