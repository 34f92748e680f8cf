"""Diagrams of the gear: bifurcation diagrams in V, Hopf curves and fold / torus / period-doubling
curves of cycles in (V, Fz). Imports the core family only."""
