"""`s2h render --motion`: compare mode off screen (no Qt), a PNG of one frame or a GIF/MP4 of the clip."""

from __future__ import annotations

import dataclasses

import imageio.v2 as imageio
import numpy as np
import pytest

from grid_text import cell_pixels, inside, intruders, text_actors, text_box
from s2h_viewer.cli import main
from s2h_viewer.io.npz import save_motion
from s2h_viewer.motions.synthesis import synthesize
from s2h_viewer.render.caption import BAND


def test_render_compare_writes_a_frame_and_a_whole_clip(sample_hands, tmp_path):
    motion = synthesize(["fist", "v_sign"], sample_hands["birch"], seed=1, name="two")
    clip = save_motion(motion, tmp_path / "two.npz")
    png, gif = tmp_path / "frame.png", tmp_path / "clip.gif"
    # two quick methods: what is drawn, not how it was computed (ASRN's 2.5 s a run, three runs)
    common = ["render", "--motion", str(clip), "--target", "laurel", "--methods", "copy,tbs_copy", "--quiet"]
    assert main([*common, "--frame", "20", "--out", str(png)]) == 0
    image = imageio.imread(png)[..., :3]
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 50  # hands and a colour scale, not a blank frame
    # under the picture a caption band says the frame (a PNG passed around names what it shows)
    band = image[-BAND:]
    assert image.shape[0] == 900 + BAND and (band < 100).any() and (band[:, -200:] == 255).all()
    other = tmp_path / "other.png"
    assert main([*common, "--frame", "21", "--out", str(other)]) == 0
    assert not np.array_equal(imageio.imread(other)[-BAND:, :, :3], band)  # frame 21's caption is not frame 20's
    assert main([*common, "--out", str(gif)]) == 0
    frames = imageio.mimread(gif, memtest=False)
    assert len(frames) == motion.n_frames
    assert not np.array_equal(frames[0], frames[len(frames) // 2])  # the hands move


def test_a_target_with_no_skin_says_its_bones_are_drawn(sample_hands, tmp_path):
    """The debug robot VRM has no mesh: its cells drew grey bones with no error colour, and nothing said why."""
    from s2h_viewer.render.compare_scene import render_comparison, result_label
    from s2h_viewer.retarget.comparison import build_comparison
    motion = synthesize(["ok"], sample_hands["birch"], seed=1, name="ok")
    bones = dataclasses.replace(sample_hands["laurel"], name="bones", mesh=None)
    comparison = build_comparison(motion, sample_hands["birch"], [sample_hands["laurel"], bones], ["tbs_copy"])
    skinned, bare = comparison.results
    assert result_label(bare).endswith(", no skin: bones") and "no skin" not in result_label(skinned)

    # drawn so a hand reads: its palm see-through in the skin's colour between the knuckles (its metacarpals alone
    # were lines from one point: a fresh-eyes user could not tell front from back on the VRM robot)
    picture = render_comparison(build_comparison(motion, sample_hands["birch"], [bones], ["tbs_copy"]),
                                tmp_path / "bones.png", size=(800, 400))
    rgb = imageio.imread(picture)[:, 400:720, :3].astype(int)  # the target's cell, short of the colour bar
    palm = (rgb[..., 0] - rgb[..., 2] > 20) & (rgb[..., 0] > 150)
    assert palm.sum() > 500, palm.sum()


def test_frame_counts_say_one_frame_and_ranges_their_ends():
    from s2h_viewer.app.exports import frames_text
    assert [frames_text(range(n), 138) for n in (138,)] == ["138 frames"]
    assert frames_text(range(40, 121), 138) == "81 frames: 40 to 120"
    assert frames_text(range(1, 2), 2) == "1 frame: 1"  # was "1 frames: 1 to 1" (a fresh-eyes user)


def test_render_refuses_a_retargets_options_without_the_motion(tmp_path, capsys):
    """`s2h render --target a.glb --methods tbs_copy` drew the sample hands' gallery and said nothing of the target:
    one error line naming the options that need --motion, and nothing written."""
    out = tmp_path / "grid.png"
    assert main(["render", "--target", "iris", "--methods", "tbs_copy", "--frame", "3", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--target, --methods, --frame draw retargets of a motion: give the --motion" in err
    assert not out.exists()
    assert main(["render", "--hands", "iris", "--out", str(out)]) == 0 and out.exists()  # the gallery as before


def test_render_compare_takes_the_camera_and_the_overlays_asked_for(sample_hands, tmp_path):
    """`--view` and `--skeleton` were read for hands in one gesture only: a compare picture always came from the
    three-quarter camera, where a pinch's touch hides behind the fingers; now they and `--contacts` act on it."""
    import pyvista as pv

    from s2h_viewer.render.compare_scene import CONTACT_COLOUR
    motion = synthesize(["ok"], sample_hands["birch"], seed=1, name="ok")
    clip = save_motion(motion, tmp_path / "ok.npz")
    common = ["render", "--motion", str(clip), "--target", "laurel", "--methods", "asrn", "--quiet",
              "--frame", str(motion.n_frames - 1)]  # the OK held: the thumb on the index tip

    def picture(*options: str) -> np.ndarray:
        out = tmp_path / f"ok{'_'.join(options)}.png"
        assert main([*common, *options, "--out", str(out)]) == 0
        return imageio.imread(out)[:-BAND, :, :3].astype(int)

    def green(image: np.ndarray) -> int:  # the kept contacts' colour
        return int((np.abs(image - np.array(pv.Color(CONTACT_COLOUR).int_rgb)).max(-1) < 12).sum())
    default, side = picture(), picture("--view", "side")
    assert np.array_equal(default, picture("--view", "three_quarter"))
    assert np.abs(default - side).max(-1).astype(bool).mean() > 0.02  # another camera: the hands drawn elsewhere
    assert green(default) == 0 and green(picture("--view", "side", "--contacts")) > 30  # the OK's touch drawn
    assert not np.array_equal(picture("--skeleton"), default)


def test_a_last_page_of_one_target_keeps_the_clip_and_the_legend_under_the_source(sample_hands):
    """A page of targets keeps its pages' rows: one target on a grid of three rows. The clip's text and the contacts'
    legend went in the source's cell (a fresh-eyes user saw the legend cover the source's hand there, and no clip
    line); they go in the cell under it, as on the other pages."""
    import pyvista as pv

    from s2h_viewer.render.compare_scene import grid_layout, populate
    from s2h_viewer.retarget.comparison import build_comparison
    motion = synthesize(["ok"], sample_hands["birch"], seed=1, name="ok")
    comparison = build_comparison(motion, sample_hands["birch"], [sample_hands["iris"]], ["tbs_copy"])
    for rows, below in ((1, False), (3, True)):
        plotter = pv.Plotter(off_screen=True, window_size=(1000, 700), **grid_layout(comparison, rows))
        try:
            hands, labels = populate(plotter, comparison)
            source = hands[0]
            assert (source.overlay.legend.renderer is not source.renderer) == below
            clip = [label for label in labels if label.text.startswith("clip: ok")]
            assert len(clip) == below and all(label.renderer is not source.renderer for label in clip)
        finally:
            plotter.close()


def test_render_compare_says_what_the_banners_say_of_a_targets_frames(tmp_path, capsys):
    """A fresh-eyes user's command-line picture showed "! frames guessed" on the RPM avatar's cells, and the
    command said nothing of it; `s2h retarget` did. Both say it now, for each target whose frames are guessed."""
    from s2h_viewer.samples import ASSETS_DIR
    rpm = ASSETS_DIR / "hands/real/RPM_Template_Mesh_XR.glb"
    assert main(["render", "--motion", str(ASSETS_DIR / "motions/real/r_hand_pinch_anim.fbx"), "--source",
                 str(ASSETS_DIR / "hands/real/r_hand_skeletal_lowres.fbx"), "--target", str(rpm), "--target", "iris",
                 "--methods", "tbs_copy", "--quiet", "--out", str(tmp_path / "pinch.png")]) == 0
    said = capsys.readouterr().out.splitlines()
    assert [line for line in said if "frames from the palm plane" in line] == [
        f"{rpm}: RPM_Template_Mesh_XR: index MCP/PIP/DIP: frames from the palm plane (a guess: no rays decided them); "
        f"retargets there may bend a finger sideways: check its frames (Annotate > Open hand...)"]
    assert said[-1] == f"wrote {tmp_path / 'pinch.png'}"


def test_render_compare_draws_a_retarget_with_its_corrections(sample_hands, tmp_path, capsys):
    """`s2h render --corrections FILE` draws the retarget the sidecar was made on fixed (a fresh-eyes user could
    not make a command-line picture of a fixed retarget); a sidecar made on a retarget the picture lacks is one
    error line naming the file."""
    from scipy.spatial.transform import Rotation

    from s2h_viewer.hand import topology as topo
    from s2h_viewer.io.corrections import CorrectionsFile, save_corrections
    from s2h_viewer.retarget.corrections import Corrections
    motion = synthesize(["ok"], sample_hands["birch"], seed=1, name="ok")
    clip = save_motion(motion, tmp_path / "ok.npz")
    last = motion.n_frames - 1
    turn = Rotation.from_rotvec([0.0, np.radians(40.0), 0.0])  # the index PIP bent 40 deg more at the end
    fixes = Corrections().with_turn(topo.ARTICULATED_NAMES.index("index_pip"), last, turn, last - 10, last)
    sidecar = save_corrections(tmp_path / "fix.corrections.json", CorrectionsFile(
        fixes, "ok", motion.n_frames, motion.fps, "birch", "laurel", "tbs_copy"))
    common = ["render", "--motion", str(clip), "--target", "laurel", "--quiet", "--frame", str(last)]
    plain, fixed = tmp_path / "plain.png", tmp_path / "fixed.png"
    assert main([*common, "--methods", "tbs_copy", "--out", str(plain)]) == 0
    assert main([*common, "--methods", "tbs_copy", "--corrections", str(sidecar), "--out", str(fixed)]) == 0
    assert f"{sidecar}: 1 correction key applied to tbs_copy -> laurel" in capsys.readouterr().out
    a, b = (imageio.imread(p)[:-BAND, :, :3].astype(int) for p in (plain, fixed))
    assert np.abs(a - b).max(-1).astype(bool).mean() > 0.002  # the finger drawn elsewhere
    assert main([*common, "--methods", "asrn", "--corrections", str(sidecar), "--out", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert "fix.corrections.json: made on tbs_copy -> laurel, which this picture does not hold (it holds asrn -> " \
           "laurel)" in err and not (tmp_path / "x.png").exists()


LONG_NAME = "laurel_exported_from_a_vendor_rig_with_a_very_long_file_name_v2"


@pytest.mark.parametrize("targets, methods", [
    (("iris", "kale", "juniper", "hazel", "elm", LONG_NAME), ("copy", "tbs_copy")),  # six short, wide rows
    (("iris",), ("copy", "tbs_copy", "dm", "asrn")),  # one row of tall, narrow cells
])
def test_off_screen_labels_stay_in_their_cells_above_the_hands(sample_hands, targets, methods):
    """`s2h render --motion`'s grid at 1000 x 700: each label inside its cell (a long target name elided with
    an ellipsis, not cut at the cell's edge), the font shrunk with a short cell but no smaller than
    MIN_LABEL_PX, nothing but the text from a cell's top down to the text's bottom, the hand whole below."""
    import pyvista as pv

    from s2h_viewer.render.compare_scene import ELLIPSIS, LABEL_PX, MIN_LABEL_PX, grid_layout, populate
    from s2h_viewer.retarget.comparison import build_comparison
    hands = {**sample_hands, LONG_NAME: dataclasses.replace(sample_hands["laurel"], name=LONG_NAME)}
    motion = synthesize(["fist", "ok", "v_sign"], sample_hands["birch"], seed=4, name="short")
    comparison = build_comparison(motion, sample_hands["birch"], [hands[t] for t in targets], list(methods))
    plotter = pv.Plotter(off_screen=True, window_size=(1000, 700), **grid_layout(comparison))
    try:
        posed, _ = populate(plotter, comparison)
        for hand in posed:
            hand.show(40)
        image = plotter.screenshot(return_img=True)
        fonts = set()
        for renderer in plotter.renderers:
            for actor in text_actors(renderer):
                assert inside(text_box(actor, renderer), cell_pixels(image, renderer)), actor.GetInput()
                fonts.add(actor.GetTextProperty().GetFontSize())
        assert min(fonts) >= MIN_LABEL_PX and (min(fonts) < LABEL_PX) == (len(targets) == 6)
        for hand in posed:
            (actor,) = text_actors(hand.renderer)
            cell, box = cell_pixels(image, hand.renderer), text_box(actor, hand.renderer)
            assert intruders(cell, box) == 0, actor.GetInput()
            below = (cell[int(np.ceil(cell.shape[0] - box[2])):] < 235).any(-1)
            assert below.mean() > 0.01 and not below[-1].any()  # the hand drawn below the text, not cut at the bottom
        titles = [text_actors(h.renderer)[0].GetInput().split("\n")[0] for h in posed]
        assert [t.endswith(ELLIPSIS) for t in titles] == [LONG_NAME in t or t.endswith(ELLIPSIS) for t in titles]
        assert all(t.startswith(("Copy -> laurel_", "TBS Copy -> laurel_")) for t in titles if t.endswith(ELLIPSIS))
        assert sum(t.endswith(ELLIPSIS) for t in titles) == (2 if len(targets) == 6 else 0)
    finally:
        plotter.close()


@pytest.fixture(scope="module")
def five_methods(sample_hands):
    """A thumbs-up between a relaxed and a spread hand, onto laurel by every method."""
    from s2h_viewer.retarget.comparison import build_comparison
    motion = synthesize(["relaxed", "thumbs_up", "spread"], sample_hands["birch"], seed=2, name="thumb")
    return build_comparison(motion, sample_hands["birch"], [sample_hands["laurel"]],
                            ["copy", "tbs_copy", "dm", "asrn", "asm_opt"])


@pytest.mark.parametrize("camera", ["palm", "side"])
def test_a_thumb_held_out_stays_in_the_narrow_cells_of_five_methods(five_methods, camera):
    """Five methods across a 790-pixel view (a fresh-eyes user's window): seen from the palm, the source's
    thumbs-up thumb ran past its cell's side and was cut, in the window and in the pictures and videos exported
    from it. The view angle is widened as far as every hand reaches over the clip, seen from the camera: no
    skin in the 4 pixels inside any cell's sides (its frame is 3 wide), on every other frame."""
    import pyvista as pv

    from s2h_viewer.render.compare_scene import ViewOptions, apply_options, fit_cells, grid_layout, populate
    plotter = pv.Plotter(off_screen=True, window_size=(790, 480), **grid_layout(five_methods))
    try:
        posed, labels = populate(plotter, five_methods)
        apply_options(plotter, posed, ViewOptions(camera=camera))
        fit_cells(plotter, posed, labels)
        closest = 1.0  # the least room, over hands and frames, between skin and a cell's side, of the cell's width
        for frame in range(0, five_methods.n_frames, 2):
            for hand in posed:
                hand.show(frame)
            plotter.render()
            image = np.asarray(plotter.screenshot(return_img=True))[..., :3].astype(int)
            for hand in posed:
                cell = cell_pixels(image, hand.renderer)
                middle = cell[cell.shape[0] // 5:-cell.shape[0] // 8]  # under the label, over a banner
                skin = (middle.max(-1) - middle.min(-1) > 60) & (middle.min(-1) < 200)  # coloured, not text
                assert not skin[:, 3:7].any() and not skin[:, -7:-3].any(), (frame, hand.hand.name)
                columns = np.flatnonzero(skin.any(0))
                closest = min(closest, min(columns[0], len(skin[0]) - 1 - columns[-1]) / len(skin[0]))
        assert closest < 0.1  # and no smaller than it must be: some hand comes near a side
    finally:
        plotter.close()


def test_a_corrected_retarget_is_fitted_where_its_frames_now_reach(sample_hands):
    """The reach a cell is fitted to is its retarget's: a correction that moves the hand moves it too."""
    import pyvista as pv
    import torch

    from s2h_viewer.hand.kinematics import forward_kinematics
    from s2h_viewer.render.compare_scene import grid_layout, populate
    from s2h_viewer.render.scene import to_view
    from s2h_viewer.retarget.comparison import build_comparison
    motion = synthesize(["fist"], sample_hands["birch"], seed=1, name="fist")
    comparison = build_comparison(motion, sample_hands["birch"], [sample_hands["laurel"]], ["tbs_copy"])
    plotter = pv.Plotter(off_screen=True, window_size=(400, 300), **grid_layout(comparison))
    try:
        posed, _ = populate(plotter, comparison)
        hand = posed[1]
        fist = hand.reach[0]
        canonical = np.zeros((motion.n_frames, 15, 4), dtype=np.float32)
        canonical[..., 0] = 1.0  # every joint at the canonical pose: fingers straight
        flat = forward_kinematics(hand.hand, torch.as_tensor(canonical))
        hand.set_result(flat, None, "flat")
        furthest = to_view(hand.hand, flat.positions[0].numpy().astype(np.float64)).max(0)
        assert np.allclose(hand.reach[0].max(0), furthest)  # the straight fingers' tips, not the fist's clip
        assert not np.allclose(fist.max(0), furthest)
    finally:
        plotter.close()


def test_a_line_too_wide_is_elided_to_its_longest_start_that_fits():
    from s2h_viewer.render.compare_scene import ELLIPSIS, elide, text_extent
    line = "TBS Copy -> generic-hand-left"
    assert elide(line, 11, 500) == line
    for width in (60, 100, 140):
        short = elide(line, 11, width)
        assert short.endswith(ELLIPSIS) and line.startswith(short[:-1]) and text_extent(short, 11)[0] <= width
        assert text_extent(line[:len(short)] + ELLIPSIS, 11)[0] > width  # a letter more would not fit


def test_an_elided_title_keeps_what_tells_its_target_apart():
    """Both hands of a character in narrow cells read "TBS Copy -> human-female…" twice (a fresh-eyes user): the
    end that tells the target apart stays after the ellipsis; a poses count is no such end."""
    from s2h_viewer.render.compare_scene import ELLIPSIS, elide, text_extent
    for line, end in (("TBS Copy -> human-female (left)", " (left)"), ("ASM-Opt -> rigify_character (fbx)", " (fbx)"),
                      ("TBS Copy -> generic-hand-right #2", " #2")):
        short = elide(line, 11, 120)
        assert short.endswith(ELLIPSIS + end) and text_extent(short, 11)[0] <= 120, short
        assert line.startswith(short[:-len(ELLIPSIS + end)])
    assert elide("kept 0.902 (10/11 poses)", 11, 60).endswith(ELLIPSIS)


def test_a_caption_fits_its_pictures_width():
    """A fresh-eyes user's 926-pixel PNG of a pose of the authored poses read as one clip cut its caption at
    "RPM_Templat": a caption shrinks to fit (no smaller than 60% of its size), past that its end is elided; a
    short one keeps its size."""
    from s2h_viewer.render.caption import add_caption, clip_at
    text = ("godot_hand_poses_r (every animation), pose Horns   frame 205/691 (692 frames)  6.83 s / 23.07 s   "
            "selected: TBS Copy (fixed) -> RPM_Template_Mesh_XR")

    def inked(width: int, line: str = text) -> tuple[int, int]:  # the dark columns' extent and the dark rows'
        band = add_caption(np.zeros((0, width, 3), np.uint8), line).min(-1) < 100
        columns, rows = np.flatnonzero(band.any(0)), np.flatnonzero(band.any(1))
        return int(columns[-1]), int(rows[-1] - rows[0] + 1)
    wide, narrow, narrowest = inked(1400), inked(926), inked(500)
    assert 900 < wide[0] < 1400 - 8  # whole at its size
    assert narrow[0] <= 926 - 8 and narrow[1] < wide[1]  # smaller, whole: it ended past 926 at its size
    assert narrowest[0] <= 500 - 8 and narrowest[1] >= 0.6 * wide[1] - 1  # no smaller than 60%, elided
    assert inked(926, "short, pose relaxed   frame 7/137")[1] == wide[1]
    labels = np.array(["", "fist"], dtype=object)  # the pose named where the clip holds one (`s2h render` too)
    assert (clip_at("short", labels, 1), clip_at("short", labels, 0), clip_at("short", None, 0)) == (
        "short, pose fist", "short", "short")


def test_the_labels_font_shrinks_with_the_cell_down_to_a_minimum():
    from s2h_viewer.render.compare_scene import LABEL_PX, MIN_LABEL_PX, label_font
    sizes = [label_font(side, side)[0] for side in (400, 200, 150, 120, 100, 80, 50)]
    assert sizes[0] == LABEL_PX and sizes[-1] == MIN_LABEL_PX and sizes == sorted(sizes, reverse=True)
    assert label_font(400, 400)[1] == 3 and label_font(400, 40)[1] == 1  # a cell too short keeps the title only


def test_a_4k_pictures_labels_grow_with_it_and_stay_in_their_cells_above_the_hands(sample_hands, tmp_path):
    """A 3840 x 2160 export's labels in proportion to the picture (they read as the window's do; they were 13 px,
    a speck), still inside their cells with the hand below them."""
    from PIL import Image

    from s2h_viewer.render.compare_scene import LABEL_PX, label_px_for, render_comparison
    from s2h_viewer.retarget.comparison import build_comparison
    assert label_px_for(720) == label_px_for(1000) == LABEL_PX and label_px_for(2160) == 28
    motion = synthesize(["fist", "ok"], sample_hands["birch"], seed=4, name="short")
    comparison = build_comparison(motion, sample_hands["birch"], [sample_hands["iris"]], ["tbs_copy"])
    heights = []
    for size in ((1280, 720), (3840, 2160)):
        image = np.asarray(Image.open(render_comparison(comparison, tmp_path / f"{size[0]}.png", 20, size=size)))
        band = image[: size[1] // 8, : size[0] // 3, :3]  # the top of the source's cell: its one-line label
        rows = np.flatnonzero((band < 80).all(-1).any(1))  # rows with black ink (the skin is lighter)
        heights.append(rows[-1] - rows[0] + 1)
    assert heights[1] > 1.8 * heights[0]  # the label about twice as tall in a picture three times taller


def test_back_faces_are_skipped_only_where_they_cannot_be_seen(sample_hands):
    import pyvista as pv

    from s2h_viewer.hand.kinematics import forward_kinematics
    from s2h_viewer.io.files import load_hand_file
    from s2h_viewer.render.compare_scene import PosedHand
    from s2h_viewer.samples import ASSETS_DIR

    webxr = load_hand_file(ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb")  # an open mesh (wrist hole)
    images, culling = [], []
    for hand, opacity in ((sample_hands["iris"], 1.0), (sample_hands["iris"], 0.5), (webxr, 1.0)):
        motion = synthesize(["fist"], hand, seed=0)
        plotter = pv.Plotter(off_screen=True, window_size=(320, 320))
        posed = PosedHand(plotter, hand, forward_kinematics(hand, motion.q_tbs), None, opacity)
        posed.show(motion.n_frames - 1)
        plotter.view_vector((0.15, 0.45, -0.85), viewup=(1.0, 0.0, 0.0))
        culling.append(posed.mesh_actor.prop.culling)
        images.append(plotter.screenshot(return_img=True).astype(int))
        posed.mesh_actor.prop.culling = "none"
        images.append(plotter.screenshot(return_img=True).astype(int))
        plotter.close()
    assert culling == ["back", "none", "none"]
    assert (images[0] != 255).any(axis=-1).mean() > 0.05  # the hand is in the picture
    assert np.abs(images[0] - images[1]).max() <= 2  # the culled closed skin looks exactly the same


def test_gif_delays_keep_the_clips_length_and_no_delay_players_stretch():
    """Delays in centiseconds add up to the clip's length; at 60 fps a frame due within 2 cs of the last is
    skipped (players show a 1 cs delay as 10 cs), so every other frame is kept and the clip keeps its time."""
    from s2h_viewer.render.gif import MIN_DELAY_CS, frame_delays
    at_30 = frame_delays(510, 30.0)
    assert len(at_30) == 510 and sum(at_30.values()) == 1700 and set(at_30.values()) == {3, 4}
    at_60 = frame_delays(120, 60.0)
    assert sum(at_60.values()) == 200 and min(at_60.values()) >= MIN_DELAY_CS and len(at_60) == 80


def test_render_compare_writes_frames_start_to_end(sample_hands, tmp_path):
    """--start 30 --end 45: sixteen frames (the end included), the first of them frame 30 of the clip."""
    motion = synthesize(["fist", "v_sign"], sample_hands["birch"], seed=1, name="two")
    clip = save_motion(motion, tmp_path / "two.npz")
    common = ["render", "--motion", str(clip), "--target", "laurel", "--methods", "tbs_copy", "--quiet"]
    for frame in (0, 30):
        assert main([*common, "--frame", str(frame), "--out", str(tmp_path / f"f{frame}.png")]) == 0
    assert main([*common, "--start", "30", "--end", "45", "--out", str(tmp_path / "part.mp4")]) == 0
    reader = imageio.get_reader(tmp_path / "part.mp4")
    assert reader.count_frames() == 16
    first = reader.get_data(0).astype(int)
    reader.close()
    at = {frame: imageio.imread(tmp_path / f"f{frame}.png")[..., :3].astype(int) for frame in (0, 30)}
    height, width = at[30].shape[:2]
    assert first.shape[:2] == (height, width)  # 1400 x 928: even, so not padded (to 16, it was 1408 x 944)
    off = {frame: np.abs(first[:height, :width] - image).mean() for frame, image in at.items()}
    assert off[30] < 2.0 and off[0] > 2 * off[30]  # frame 30 (H.264 loses a little), not the clip's first
    assert main([*common, "--start", "30", "--end", "45", "--out", str(tmp_path / "part.gif")]) == 0
    assert len(imageio.mimread(tmp_path / "part.gif", memtest=False)) == 16  # a GIF the same (30 fps: none skipped)


def test_render_compare_refuses_frames_the_clip_has_not(sample_hands, tmp_path, capsys):
    """Out of the clip, backwards, or a range for a PNG: one line naming the clip's frame count, nothing written."""
    motion = synthesize(["fist"], sample_hands["birch"], seed=1, name="one")
    clip = save_motion(motion, tmp_path / "one.npz")
    n = motion.n_frames
    common = ["render", "--motion", str(clip), "--target", "laurel", "--methods", "tbs_copy", "--quiet"]
    for asked, out, said in ((["--start", "5", "--end", str(n)], "a.mp4", f"frames 5 to {n} are not all in the clip"),
                             (["--start", "-1"], "b.gif", f"frames -1 to {n - 1} are not all in the clip"),
                             (["--start", "20", "--end", "10"], "c.mp4", "frames 20 to 10: the first comes after"),
                             (["--frame", str(n)], "d.png", f"frame {n} is not in the clip"),
                             (["--start", "2"], "e.png", "--start and --end choose the frames of a video")):
        assert main([*common, *asked, "--out", str(tmp_path / out)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("s2h: error: ") and said in err and len(err.strip().splitlines()) == 1
        assert out == "e.png" or f"has {n} frames (0 to {n - 1})" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["one.npz"]


def test_a_mitten_avatars_bones_are_drawn_over_its_skin(sample_hands, tmp_path):
    """cryptovoxels.vrm's hand is one paddle that does not part the fingers (the solver says so): its skin cannot
    show what they do, so its skeleton is drawn over the skin made see-through, the overlay switched off or not;
    a hand whose mesh parts its fingers keeps its skin as it is."""
    import pyvista as pv

    from s2h_viewer.annotate.trust import frame_warning
    from s2h_viewer.io.files import RigOptions, load_hand_file
    from s2h_viewer.render.compare_scene import (SKELETON_OPACITY, ViewOptions, apply_options, grid_layout, populate,
                                                 result_label)
    from s2h_viewer.retarget.comparison import build_comparison
    from s2h_viewer.samples import ASSETS_DIR

    mitten = load_hand_file(ASSETS_DIR / "hands" / "real" / "cryptovoxels.vrm", RigOptions(side="right"))
    assert mitten.meta["unparted_fingers"] == ["middle", "ring", "pinky"]
    warning = frame_warning(mitten)  # its tooltip says why the bones are drawn
    assert warning is not None and warning.unparted == ("middle", "ring", "pinky")
    assert "does not part middle, ring, pinky from their neighbours (a mitten)" in warning.describe()
    source = sample_hands["birch"]
    comparison = build_comparison(synthesize(["fist"], source, seed=0), source, [mitten, sample_hands["iris"]],
                                  ["tbs_copy"])
    plotter = pv.Plotter(off_screen=True, window_size=(900, 400), **grid_layout(comparison))
    hands, _ = populate(plotter, comparison)
    apply_options(plotter, hands, ViewOptions())
    drawn = {hand.hand.name: (hand.overlay.show_skeleton, hand.mesh_actor.prop.opacity) for hand in hands}
    plotter.close()
    assert drawn[mitten.name] == (True, pytest.approx(SKELETON_OPACITY))
    assert drawn["iris"] == (False, 1.0) and drawn["birch"] == (False, 1.0)
    labels = {r.target.name: result_label(r) for r in comparison.results}  # the cell says why its skin is see-through
    assert labels[mitten.name].endswith(", mitten: bones") and "mitten" not in labels["iris"]
