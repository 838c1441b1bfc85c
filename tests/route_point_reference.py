"""``sonar_gym.polyline.Route.xy_at`` as it was written with ``min`` and ``max``, kept as the
tests' reference for its comparison form."""

from __future__ import annotations

import bisect

from sonar_gym.polyline import Route


def xy_at_reference(route: Route, s_m: float) -> tuple[float, float]:
    """The point at route length ``s_m`` (clipped to the route), as Python floats."""
    cumulative, vertices = route.cumulative_m.tolist(), route.vertices.tolist()
    s = min(max(s_m, 0.0), cumulative[-1])
    index = bisect.bisect_right(cumulative, s) - 1  # np.searchsorted(..., side="right")
    index = min(max(index, 0), len(vertices) - 2)
    span = cumulative[index + 1] - cumulative[index]
    fraction = 0.0 if span <= 0.0 else (s - cumulative[index]) / span
    (x0, y0), (x1, y1) = vertices[index], vertices[index + 1]
    return x0 + fraction * (x1 - x0), y0 + fraction * (y1 - y0)
