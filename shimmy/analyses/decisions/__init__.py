"""Design decisions: the design space, sensitivities, the optimiser, robustness under tolerances and
parametric studies. May import every other family."""
