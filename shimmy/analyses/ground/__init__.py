"""Ground runs: take-off, landing-roll and taxi profiles V(t), Fz(t), and the gear's response along
them against the Hopf and cycle curves. Imports the core and diagrams families."""
