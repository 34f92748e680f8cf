"""(V, Fz) stability maps: slices, shading between the curves, and the design figures of merit read
off a map. Imports the core and diagrams families."""
