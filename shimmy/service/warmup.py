"""Kernels loaded before a web worker answers: the numba-compiled model and integrator are compiled
(or, with numba's on-disk cache, loaded) on their first call, 0.7 s in a process whose cache is
warm and about 7 s where it is empty; the first user of a fresh server waited that long for the
first Overview figure with nothing saying why. gunicorn.conf.py calls :func:`warm_kernels` in each
worker before it takes requests.

Every analysis the web worker answers in the request (``sync``) is run once on a small question,
outside the result cache, so that nothing is stored and each of its kernels is loaded; but the
sensitivities, seconds of work whose kernels (the gear's equations, the eigenvalues of x = 0) the
stability and Hopf questions load already.
"""

from __future__ import annotations

import time

from . import analyses, schemas

#: A small question per analysis answered in the request: each kernel it uses runs once.
QUESTIONS = {
    "simulate": {"config": "nes_pd", "V": 50.0, "Fz": 150e3, "t_end": 0.2, "include_series": True},
    "hopf": {"config": "nes_pd", "Fz": 150e3},
    "stability": {"Fz": 150e3, "n_points": 10},
    "devices": {},
}


def warm_kernels() -> float:
    """Run each of :data:`QUESTIONS` (the cache neither read nor written); the seconds it took."""
    clock = time.perf_counter()
    for name, body in QUESTIONS.items():
        analyses.ANALYSES[name].runner(schemas.validate(name, body), None)
    return time.perf_counter() - clock
