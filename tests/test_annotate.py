"""The TBS ray solver against procedural ground truth, its diagnostics, and the annotation sidecar."""

from __future__ import annotations

import dataclasses
import json
import shutil

import numpy as np
import pytest

from s2h_viewer.annotate.report import annotation_report
from s2h_viewer.annotate.solver import frame_angle_errors, palm_plane_frames, solve_tbs_frames
from s2h_viewer.errors import InputFileError, InvalidHandError
from s2h_viewer.hand import topology as topo
from s2h_viewer.io.annotation import Annotation, load_annotation, save_annotation, sidecar_path
from s2h_viewer.io.gltf import load_gltf_hand
from s2h_viewer.samples import ASSETS_DIR, hand_names

TEST_HANDS = hand_names("test")


@pytest.mark.parametrize("name", TEST_HANDS)
def test_solver_finds_the_true_frames_of_every_test_hand(sample_hands, name):
    hand = sample_hands[name]
    solution = solve_tbs_frames(hand)
    errors = frame_angle_errors(solution.frames, hand.rest_frames)
    assert np.mean(errors <= 10.0) >= 0.95, np.round(errors, 1)
    assert not solution.fallback.any() and solution.hit_fraction.min() > 0.9
    # the frames are proper right-handed rotations with the twist along the bone
    np.testing.assert_allclose(np.linalg.det(solution.frames), 1.0, atol=1e-9)
    np.testing.assert_allclose(solution.frames[:, :, 0], hand.rest_frames[:, :, 0], atol=1e-9)


def test_solver_does_not_read_the_frames_it_is_compared_with(sample_hands):
    hand = sample_hands["iris"]
    scrambled = dataclasses.replace(hand, rest_frames=palm_plane_frames(hand.rest_positions))
    np.testing.assert_allclose(solve_tbs_frames(scrambled).frames, solve_tbs_frames(hand).frames)


def test_joint_outside_the_mesh_falls_back_and_is_flagged(sample_hands):
    hand = sample_hands["kale"]
    mesh = dataclasses.replace(hand.mesh, vertices=hand.mesh.vertices + np.float32([0.0, 0.0, 1.0]))  # moved away
    solution = solve_tbs_frames(dataclasses.replace(hand, mesh=mesh))
    assert solution.fallback.all() and solution.needs_review.all()
    assert "no ray hit the mesh" in solution.diagnostics[0]
    np.testing.assert_allclose(solution.frames, palm_plane_frames(hand.rest_positions))


def test_hand_without_mesh_is_refused(sample_hands):
    with pytest.raises(InvalidHandError, match="has no mesh"):
        solve_tbs_frames(dataclasses.replace(sample_hands["iris"], mesh=None))


def test_report_table_has_a_row_per_hand_and_the_overall_share(sample_hands):
    results = [(sample_hands[n], solve_tbs_frames(sample_hands[n]), 0.1) for n in TEST_HANDS]
    text = annotation_report(results, against_truth=True)
    assert all(f"| {n} |" in text for n in TEST_HANDS)
    assert "100.0% within 10 deg" in text


def test_sidecar_round_trip_is_loaded_with_the_hand_and_pinned_to_its_file(tmp_path):
    glb = shutil.copy(ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb", tmp_path / "hand.glb")
    solved = load_gltf_hand(glb)
    assert solved.meta["annotation"] == "solver"
    frames = solved.rest_frames.copy()
    j = topo.ARTICULATED_NAMES.index("index_mcp")
    twist = frames[j][:, 0]  # a manual correction: index MCP turned 20 degrees about its twist axis
    angle = np.radians(20.0)
    k = np.array([[0, -twist[2], twist[1]], [twist[2], 0, -twist[0]], [-twist[1], twist[0], 0]])
    frames[j] = (np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k) @ frames[j]
    set_by = ["solver"] * topo.N_ARTICULATED
    set_by[j] = "manual"
    path = save_annotation(Annotation(frames, set_by, np.ones(topo.N_ARTICULATED)), glb, "right")
    assert path == sidecar_path(glb, "right") and path.name == "hand.right.tbs.json"
    document = json.loads(path.read_text())
    assert document["schema"] == "s2h-tbs-annotation" and document["version"] == 2 and document["side"] == "right"
    assert document["joints"]["index_mcp"]["set_by"] == "manual"
    annotated = load_gltf_hand(glb)
    assert annotated.meta["annotation"] == "sidecar"
    np.testing.assert_allclose(annotated.rest_frames, frames, atol=1e-7)
    # the hand file changes: its old annotation is refused, not applied
    data = bytearray(glb.read_bytes())
    data[-1] ^= 0xFF
    glb.write_bytes(bytes(data))
    with pytest.raises(InputFileError, match=r"hand\.right\.tbs\.json: was made for a different version of hand\.glb"):
        load_annotation(glb, "right")


@pytest.mark.parametrize("edit,message", [
    (lambda d: d.update(version=9), "annotation version 9 is not supported"),
    (lambda d: d["joints"].pop("pinky_dip"), "no frame for pinky_dip"),
    (lambda d: d["joints"]["thumb_ip"].update(frame=[[1, 0, 0], [0, 1, 0], [0, 0, -1]]), "not right-handed"),
    (lambda d: d["joints"]["thumb_ip"].update(set_by="robot"), "unknown set_by value"),
])
def test_damaged_sidecars_give_clear_errors(sample_hands, tmp_path, edit, message):
    hand_file = tmp_path / "h.npz"
    hand_file.write_bytes(b"hand")
    hand = sample_hands["iris"]
    path = save_annotation(Annotation(hand.rest_frames, ["solver"] * 15, np.ones(15)), hand_file, "right")
    document = json.loads(path.read_text())
    edit(document)
    path.write_text(json.dumps(document))
    with pytest.raises(InputFileError, match=message):
        load_annotation(hand_file, "right")
    path.write_text("{not json")
    with pytest.raises(InputFileError, match=r"h\.right\.tbs\.json: not valid JSON"):
        load_annotation(hand_file, "right")


def test_a_session_opens_with_the_sidecars_set_by_and_confidence_and_keeps_manual_frames_on_request(tmp_path):
    from s2h_viewer.annotate.editing import AnnotationSession, rotate_about_twist
    glb = shutil.copy(ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb", tmp_path / "hand.glb")
    fresh = AnnotationSession.open(load_gltf_hand(glb), glb)
    solution = solve_tbs_frames(fresh.hand)
    assert fresh.frames_from == "solver" and fresh.set_by == ["solver"] * topo.N_ARTICULATED
    np.testing.assert_allclose(fresh.confidence, solution.confidence)  # scored, not a blanket 1.0
    fresh.frames[2] = rotate_about_twist(fresh.frames[2], 35.0)
    fresh.set_by[2] = "manual"
    fresh.confidence[5] = np.nan  # a frame nobody scored is written as null and read back as NaN
    save_annotation(fresh.annotation(), glb, "right")
    assert json.loads(sidecar_path(glb, "right").read_text())["joints"][topo.ARTICULATED_NAMES[5]]["confidence"] is None

    reopened = AnnotationSession.open(load_gltf_hand(glb), glb)
    assert reopened.frames_from == "sidecar" and reopened.set_by == fresh.set_by
    np.testing.assert_allclose(reopened.confidence, fresh.confidence, atol=1e-4, equal_nan=True)
    np.testing.assert_allclose(reopened.frames, fresh.frames, atol=1e-7)
    assert reopened.describe(2).endswith(": manual") and "not scored" in reopened.describe(5)

    kept = reopened.frames[2].copy()
    reopened.apply_solution(solution, keep_manual=True)
    np.testing.assert_allclose(reopened.frames[2], kept)
    assert reopened.manual_joints() == [2]
    np.testing.assert_allclose(np.delete(reopened.frames, 2, 0), np.delete(solution.frames, 2, 0))
    reopened.apply_solution(solution)
    assert reopened.manual_joints() == [] and np.allclose(reopened.frames, solution.frames)


def test_drag_geometry_signed_angles_rays_and_turns_past_half_a_circle():
    from s2h_viewer.annotate.editing import ray_plane_point, ring_polyline, signed_angle_about, unwrap_degrees
    axis = np.array([0.0, 0.0, 2.0])
    assert signed_angle_about(axis, np.array([1.0, 0, 0]), np.array([0, 1.0, 0])) == pytest.approx(90.0)
    assert signed_angle_about(-axis, np.array([1.0, 0, 0]), np.array([0, 1.0, 0])) == pytest.approx(-90.0)
    centre = np.array([0.0, 0.0, 1.0])
    hit = ray_plane_point(np.array([0.3, 0.2, 5.0]), np.array([0.0, 0.0, -1.0]), centre, axis)
    np.testing.assert_allclose(hit, [0.3, 0.2, 1.0])
    assert ray_plane_point(np.zeros(3), np.array([1.0, 0.0, 0.05]), centre, axis) is None  # along the plane
    assert ray_plane_point(np.zeros(3), np.array([0.0, 0.0, -1.0]), centre, axis) is None  # away from it
    total, last = 0.0, 0.0
    for angle in (90.0, 170.0, -170.0, -90.0, 0.0):  # one full turn, seen as angles in (-180, 180]
        total, last = unwrap_degrees(total, last, angle), angle
    assert total == pytest.approx(360.0)
    frame = np.eye(3)
    points = ring_polyline(centre, frame, 0.5, n=8)
    np.testing.assert_allclose(points[0], centre + [0, 0.5, 0])  # angle 0 on the bend axis
    np.testing.assert_allclose(np.linalg.norm(points - centre, axis=1), 0.5)
    np.testing.assert_allclose((points - centre) @ frame[:, 0], 0.0, atol=1e-12)
