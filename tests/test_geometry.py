"""The one distance-to-segment helper the solver, the compare grid and the rotation ring's picking share."""
import numpy as np

from s2h_viewer.geometry import distance_to_segments


def test_distances_to_segments_match_the_nearest_of_many_points_along_each():
    """Random points and segments in 3-D and on screen (2-D), broadcast one point against many segments and
    many points against one: each distance is the nearest of 20001 points sampled along its segment, and the
    projection is clamped (a point beyond an end is as far as that end)."""
    rng = np.random.default_rng(0)
    along = np.linspace(0.0, 1.0, 20001)[:, None]
    for dim in (3, 2):
        points, starts, ends = (rng.normal(size=(200, dim)) for _ in range(3))
        sampled = np.array([np.linalg.norm(s + along * (e - s) - p, axis=1).min()
                            for p, s, e in zip(points, starts, ends)])
        np.testing.assert_allclose(distance_to_segments(points, starts, ends), sampled, atol=2e-4)
        np.testing.assert_allclose(distance_to_segments(points[0], starts, ends),
                                   [distance_to_segments(points[0], s, e) for s, e in zip(starts, ends)])
        np.testing.assert_allclose(distance_to_segments(points, starts[0], ends[0]),
                                   [distance_to_segments(p, starts[0], ends[0]) for p in points])
        beyond = ends[0] + 2.0 * (ends[0] - starts[0])
        np.testing.assert_allclose(distance_to_segments(beyond, starts[0], ends[0]),
                                   2.0 * np.linalg.norm(ends[0] - starts[0]))


def test_a_segment_of_length_zero_is_its_point():
    """Two joints at one place (a degenerate bone) give the distance to that place, not a NaN."""
    point, at = np.array([3.0, 4.0, 0.0]), np.zeros(3)
    assert distance_to_segments(point, at, at) == 5.0
    assert distance_to_segments(at, at, at) == 0.0
