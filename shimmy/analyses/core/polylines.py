"""Where a point lies relative to a computed curve drawn as a polyline (scaled coordinates)."""

from __future__ import annotations

import math

import numpy as np


def nearest_on_polyline(points: np.ndarray, q: np.ndarray) -> tuple[int, float, float, float] | None:
    """(segment i, fraction s along it, distance, segment length) of the point of the polyline
    ``points`` (k, d) nearest to ``q`` (d,); None for fewer than two points."""
    if len(points) < 2:
        return None
    a, b = points[:-1], points[1:]
    d = b - a
    length2 = np.maximum(np.sum(d * d, axis=1), 1e-300)
    s = np.clip(np.sum((q - a) * d, axis=1) / length2, 0.0, 1.0)
    dist = np.linalg.norm(a + s[:, None] * d - q, axis=1)
    i = int(np.argmin(dist))
    return i, float(s[i]), float(dist[i]), math.sqrt(float(length2[i]))


def near_polyline(points: np.ndarray, q: np.ndarray) -> tuple[int, float] | None:
    """(segment, fraction) where ``q`` lies on the polyline: within a fifth of the local step, far
    above the chord error of a continued curve at its step sizes; else None."""
    hit = nearest_on_polyline(points, q)
    if hit is None or hit[2] > 0.2 * hit[3] + 1e-6:
        return None
    return hit[0], hit[1]
