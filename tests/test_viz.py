"""hugger.viz: the paper's figures, the TipState plot, animations and render() (matplotlib extra)."""
from __future__ import annotations

import dataclasses
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import hugger
from hugger import viz

HAVE_MPL = True
try:
    import matplotlib  # noqa: F401
except ImportError:
    HAVE_MPL = False
needs_mpl = pytest.mark.skipif(not HAVE_MPL, reason="matplotlib is not installed (pip install 'hugger[viz]')")


def _turned(pose: np.ndarray, degrees: float) -> np.ndarray:
    """``pose`` turned about its own (the palm's) x axis."""
    a = np.radians(degrees)
    rx = np.eye(4)
    rx[1:3, 1:3] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
    return pose @ rx


@pytest.fixture(scope="module")
def turned_plan(hand, sphere):
    """5x5 hand around a 4 cm sphere, starting turned 60 degrees away from T: Phase 1 has work."""
    traj = hugger.plan(hand, sphere, [0, 0, 0], _turned(hugger.look_at([0, 0, 0.2], [0, 0, 0]), 60.0))
    assert np.any(traj.phase == 1) and traj.status == "done"
    return traj


@pytest.fixture(scope="module")
def facing_plan(hand, sphere):
    """The same hand already facing T: no Phase 1."""
    traj = hugger.plan(hand, sphere, [0, 0, 0], hugger.look_at([0.03, 0.02, 0.16], [0, 0, 0]))
    assert not np.any(traj.phase == 1)
    return traj


@pytest.fixture(scope="module")
def small_plan():
    """A small, quick plan (3 fingers x 3 zero-radius links, as in the paper) for animations."""
    hand = hugger.Hand(fingers=3, links=3, link_length=0.03, link_radius=0.0, palm_radius=0.025, palm_thickness=0.01)
    obj = hugger.objects.blob(radius=0.035, seed=3, subdivisions=2)
    return hugger.plan(hand, obj, [0, 0, 0], _turned(hugger.look_at([0, 0, 0.16], [0, 0, 0]), 40.0))


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    if HAVE_MPL and "matplotlib.pyplot" in sys.modules:
        sys.modules["matplotlib.pyplot"].close("all")


def _read_png(path, size_inches, dpi):
    from PIL import Image

    assert path.is_file() and path.stat().st_size > 0
    with Image.open(path) as im:
        assert im.format == "PNG"
        assert im.size == (round(size_inches[0] * dpi), round(size_inches[1] * dpi))
        pixels = np.asarray(im.convert("RGB"))
    return pixels


def _assert_a_picture(pixels: np.ndarray) -> None:
    """Not one colour, and more than a handful of colours (shading, not flat fills only)."""
    flat = pixels.reshape(-1, 3)
    assert np.ptp(flat, axis=0).max() > 100
    assert len(np.unique(flat, axis=0)) > 200


def _panel_ks(fig) -> list[int]:
    return [int(re.search(r"k = (\d+)", ax.get_title()).group(1)) for ax in fig.axes if ax.name == "3d"]


def _assert_drawing_inside_axes(fig, traj, ks=None) -> None:
    """Every joint of the drawn configurations projects inside its axes (nothing clipped off)."""
    from mpl_toolkits.mplot3d import proj3d

    fig.canvas.draw()
    scene = viz._Scene(traj, 2000)
    for ax, k in zip([a for a in fig.axes if a.name == "3d"], _panel_ks(fig) if ks is None else ks):
        p = scene.to_display(traj.joints[k].reshape(-1, 3))
        xs, ys, _ = proj3d.proj_transform(p[:, 0], p[:, 1], p[:, 2], ax.get_proj())
        px = ax.transData.transform(np.column_stack([xs, ys]))
        box = ax.bbox
        assert np.all(px[:, 0] > box.x0) and np.all(px[:, 0] < box.x1), ax.get_title()
        assert np.all(px[:, 1] > box.y0) and np.all(px[:, 1] < box.y1), ax.get_title()


# --- import and optional dependencies ------------------------------------------------------------

def test_importing_viz_does_not_import_matplotlib():
    code = "import sys, hugger, hugger.viz; sys.exit(1 if 'matplotlib' in sys.modules else 0)"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr or "importing hugger.viz imported matplotlib"


@needs_mpl
@pytest.mark.parametrize("env_backend, expected", [(None, "agg"), ("svg", "svg")])
def test_agg_is_chosen_only_when_no_backend_is_set(env_backend, expected):
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    if env_backend:
        env["MPLBACKEND"] = env_backend
    code = "import hugger.viz as v, matplotlib; v.require(); print(matplotlib.get_backend().lower())"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == expected


@pytest.mark.parametrize("call", [
    lambda t, d: viz.fig4(t),
    lambda t, d: viz.fig5(t),
    lambda t, d: viz.tipstate_plot(t),
    lambda t, d: viz.render(t, d / "x.png"),
    lambda t, d: viz.animate(t, d / "x.gif"),
    lambda t, d: viz.require(),
])
def test_missing_matplotlib_names_the_viz_extra(call, small_plan, tmp_path, monkeypatch):
    for name in list(sys.modules):
        if name == "matplotlib" or name.startswith(("matplotlib.", "mpl_toolkits")):
            monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # "import matplotlib" now raises ImportError
    with pytest.raises(ImportError, match=re.escape("pip install 'hugger[viz]'")):
        call(small_plan, tmp_path)
    assert not list(tmp_path.iterdir())


@needs_mpl
def test_missing_ffmpeg_names_what_to_install(small_plan, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)
    monkeypatch.setattr(viz.shutil, "which", lambda name: None)
    assert viz.ffmpeg_path() is None
    with pytest.raises(ImportError, match="imageio-ffmpeg"):
        viz.animate(small_plan, tmp_path / "x.mp4", max_frames=2)
    assert not (tmp_path / "x.mp4").exists()


# --- bad input ---------------------------------------------------------------------------------------

@needs_mpl
@pytest.mark.parametrize("call, match", [
    (lambda t, d: viz.render(t, d / "x.txt"), r"\.png"),
    (lambda t, d: viz.render(t, d / "noextension"), r"\.gif"),
    (lambda t, d: viz.animate(t, d / "x.png"), r"\.gif or \.mp4"),
    (lambda t, d: viz.fig4(t, d / "x.gif"), r"\.png"),
    (lambda t, d: viz.fig5(t, d / "x.jpg"), r"\.png"),
    (lambda t, d: viz.tipstate_plot(t, d / "x.mp4"), r"\.png"),
    (lambda t, d: viz.animate(t, d / "x.gif", fps=0), "fps"),
    (lambda t, d: viz.animate(t, d / "x.gif", fps=float("nan")), "fps"),
    (lambda t, d: viz.animate(t, d / "x.gif", max_frames=0), "max_frames"),
    (lambda t, d: viz.animate(t, d / "x.gif", max_frames=2.5), "max_frames"),
    (lambda t, d: viz.animate(t, d / "x.gif", progress="yes"), "progress"),
    (lambda t, d: viz.animate(t, d / "x.gif", view="top"), "view"),
    (lambda t, d: viz.fig4(t, dpi=-1), "dpi"),
    (lambda t, d: viz.fig5(t, d / "x.png", dpi=100000), "dpi must be at most 1200"),
    (lambda t, d: viz.tipstate_plot(t, d / "x.png", dpi=1e9), "dpi must be at most 1200"),
    (lambda t, d: viz.animate(t, d / "x.gif", fps=1e9), "fps must be at most 120"),
    (lambda t, d: viz.animate(t, d / "x.gif", hold=3600), "hold must be at most 10"),
    (lambda t, d: viz.animate(t, d / "x.gif", dpi=5000), "dpi must be at most 1200"),
    (lambda t, d: viz.fig4(t, d / "x.png", dpi=2), "dpi must be at least 10"),  # FreeType refused the fonts
    (lambda t, d: viz.animate(t, d / "x.gif", max_frames=2, dpi=1), "dpi must be at least 10"),
    (lambda t, d: viz.tipstate_plot(t, max_samples=0), "max_samples"),
    (lambda t, d: viz.fig5(t, max_faces=3), "max_faces"),
    (lambda t, d: viz.fig4("plan.npz"), "hugger.Trajectory"),
])
def test_bad_input_raises_value_error_and_writes_nothing(call, match, small_plan, tmp_path):
    with pytest.raises(ValueError, match=match):
        call(small_plan, tmp_path)
    assert not list(tmp_path.iterdir())


@needs_mpl
@pytest.mark.parametrize("write", [lambda t, p: viz.fig5(t, p.with_suffix(".png"), dpi=30),
                                   lambda t, p: viz.animate(t, p.with_suffix(".gif"), max_frames=3, dpi=30)])
def test_figures_and_animations_are_written_atomically(write, small_plan, tmp_path, monkeypatch):
    # A writer that fails midway (a full disk, say) leaves nothing under the final name, nor a
    # temporary file; one that succeeds leaves the file alone.
    from matplotlib.figure import Figure
    from matplotlib.animation import PillowWriter

    def fail(path):  # half the file written, then the disk is full
        Path(path).write_bytes(b"half a file")
        raise OSError(28, "No space left on device")

    savefig = Figure.savefig
    with monkeypatch.context() as m:  # (a GIF's frames are saved to memory: those work)
        m.setattr(Figure, "savefig", lambda fig, fname, **kwargs: fail(fname) if isinstance(fname, (str, os.PathLike))
                  else savefig(fig, fname, **kwargs))
        m.setattr(PillowWriter, "finish", lambda writer: fail(writer.outfile))
        with pytest.raises(OSError, match="No space left on device"):
            write(small_plan, tmp_path / "out")
    assert not list(tmp_path.iterdir())
    write(small_plan, tmp_path / "out")
    assert [f.name for f in tmp_path.iterdir()] in (["out.png"], ["out.gif"])


# --- Fig. 4 ----------------------------------------------------------------------------------------------

@needs_mpl
def test_fig4_six_panels_with_phase1(turned_plan, tmp_path):
    path = tmp_path / "new" / "folder" / "fig4.png"  # the parent folders are created
    fig = viz.fig4(turned_plan, path, dpi=50)
    _assert_a_picture(_read_png(path, viz.FIG4_SIZE, 50))
    ks = _panel_ks(fig)
    assert len(ks) == 6 and ks == sorted(set(ks))
    titles = [ax.get_title() for ax in fig.axes if ax.name == "3d"]
    assert [t[:3] for t in titles] == ["(a)", "(b)", "(c)", "(d)", "(e)", "(f)"]
    phase, state = turned_plan.phase, turned_plan.tip_state
    assert ks[0] == 0 and ks[-1] == len(turned_plan) - 1
    assert ks[1] == np.flatnonzero(phase == 1)[-1]  # (b): the end of Phase 1, palm facing T
    assert ks[2] == np.flatnonzero(np.any(state != hugger.FROZEN, axis=1))[0]  # (c): first contact
    assert all(phase[k] == 2 for k in ks[2:])
    for title, k in zip(titles, ks):
        assert (f"Phase {phase[k]}" if phase[k] else "C_init") in title
    assert "Phase 1" in titles[1] and "first contact" in titles[2]


@needs_mpl
def test_fig4_without_phase1_leaves_that_panel_out(facing_plan):
    fig = viz.fig4(facing_plan)
    ks = _panel_ks(fig)
    assert len(ks) == 5 and ks == sorted(set(ks)) and ks[0] == 0 and ks[-1] == len(facing_plan) - 1
    assert not any("Phase 1" in ax.get_title() for ax in fig.axes)
    _assert_drawing_inside_axes(fig, facing_plan)


def _first(traj: hugger.Trajectory, n: int) -> hugger.Trajectory:
    """The plan cut after its first n configurations."""
    keys = ("palm_pose", "joints", "angles", "tip_state", "phase")
    return dataclasses.replace(traj, **{key: getattr(traj, key)[:n] for key in keys})


@needs_mpl
def test_fig4_of_a_short_plan_has_distinct_panels(turned_plan):
    ks = _panel_ks(viz.fig4(_first(turned_plan, 4)))  # C_init and three Phase 1 configurations
    assert ks == [0, 3]
    assert _panel_ks(viz.fig4(_first(turned_plan, 1))) == [0]
    contact = int(np.flatnonzero(np.any(turned_plan.tip_state != hugger.FROZEN, axis=1))[0])
    ks = _panel_ks(viz.fig4(_first(turned_plan, contact + 3)))  # ends just after the first contact
    assert ks == sorted(set(ks)) and ks[-1] == contact + 2 and contact in ks


@needs_mpl
def test_fig4_of_a_plan_stopped_before_any_contact(hand, sphere):
    traj = hugger.plan(hand, sphere, [0, 0, 0], hugger.look_at([0, 0, 0.2], [0, 0, 0]), max_iterations=5)
    assert traj.status == "max_iterations" and not np.any(traj.tip_state != hugger.FROZEN)
    fig = viz.fig4(traj)
    titles = [ax.get_title() for ax in fig.axes if ax.name == "3d"]
    ks = _panel_ks(fig)
    assert ks[:2] == [0, 1] and ks[-1] == len(traj) - 1 and ks == sorted(set(ks))
    assert "Phase 2 starts" in titles[1] and not any("first contact" in t for t in titles)


@needs_mpl
def test_draw_configuration_into_your_own_axes(small_plan):
    import matplotlib.pyplot as plt

    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    artists = viz.draw_configuration(ax, small_plan, -1, view="oblique", limits=([-0.1] * 3, [0.1] * 3))
    assert len(artists) >= 3  # the scene, T and the contacts
    assert ax.get_xlim() == pytest.approx((-0.1, 0.1))
    with pytest.raises(ValueError, match="limits"):
        viz.draw_configuration(ax, small_plan, 0, limits=([0.1] * 3, [-0.1] * 3))
    with pytest.raises(IndexError):
        viz.draw_configuration(ax, small_plan, len(small_plan))


# --- Fig. 5 and the overview ------------------------------------------------------------------------------

@needs_mpl
def test_fig5_two_views_of_the_final_grasp(turned_plan, tmp_path):
    fig = viz.fig5(turned_plan, tmp_path / "fig5.png", dpi=60)
    _assert_a_picture(_read_png(tmp_path / "fig5.png", viz.FIG5_SIZE, 60))
    axes = [ax for ax in fig.axes if ax.name == "3d"]
    assert len(axes) == 2
    assert {round(ax.elev) for ax in axes} == {round(viz._SIDE.elev), round(viz._ALONG_NORMAL.elev)}
    s = turned_plan.summary()
    assert f"{s['links_in_contact']} of {s['links']} links" in fig._suptitle.get_text()
    _assert_drawing_inside_axes(fig, turned_plan, [len(turned_plan) - 1] * 2)


@needs_mpl
def test_render_png_is_the_overview_and_pdf_svg_work(turned_plan, tmp_path):
    calls = []
    out = viz.render(turned_plan, tmp_path / "grasp.PNG", dpi=40, progress=lambda i, n: calls.append((i, n)))
    assert out == tmp_path / "grasp.PNG" and calls == [(1, 1)]
    _assert_a_picture(_read_png(out, viz.OVERVIEW_SIZE, 40))
    viz.render(turned_plan, tmp_path / "grasp.svg", max_faces=500)
    assert (tmp_path / "grasp.svg").read_text().lstrip().startswith("<?xml")
    viz.render(turned_plan, tmp_path / "grasp.pdf", max_faces=500)
    assert (tmp_path / "grasp.pdf").read_bytes()[:5] == b"%PDF-"


@needs_mpl
def test_returned_figure_stays_open_until_saved(small_plan, tmp_path):
    import matplotlib.pyplot as plt

    fig = viz.fig5(small_plan)
    assert plt.fignum_exists(fig.number)
    fig = viz.fig5(small_plan, tmp_path / "f.png")
    assert not plt.fignum_exists(fig.number)


# --- drawing details ---------------------------------------------------------------------------------------

@needs_mpl
def test_display_frame_puts_the_final_palm_normal_down(turned_plan):
    scene = viz._Scene(turned_plan, 2000)
    assert np.allclose(scene.rot @ scene.rot.T, np.eye(3)) and np.isclose(np.linalg.det(scene.rot), 1.0)
    assert np.allclose(scene.rot @ turned_plan.palm_pose[-1][:3, 2], [0, 0, -1])
    assert np.allclose(scene.to_display(turned_plan.target), 0.0)


def test_decimation_keeps_the_shape_and_respects_the_budget():
    v, f = hugger.objects.icosphere(4)  # 5120 triangles
    v2, f2 = viz._decimate(v, f, 800)
    assert 100 < len(f2) <= 800
    assert f2.min() >= 0 and f2.max() < len(v2)
    assert np.all((f2[:, 0] != f2[:, 1]) & (f2[:, 1] != f2[:, 2]) & (f2[:, 0] != f2[:, 2]))
    assert np.abs(np.linalg.norm(v2, axis=1) - 1.0).max() < 0.1  # still (nearly) on the unit sphere

    def area(vv, ff):
        t = vv[ff]
        return 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum()

    assert abs(area(v2, f2) / area(v, f) - 1.0) < 0.06
    same_v, same_f = viz._decimate(v, f, 10_000)
    assert same_v is v and same_f is f


def test_contact_marks_are_the_analysis_contacts_on_the_hand(turned_plan):
    from hugger import analysis

    obj = turned_plan.object()
    pts = viz._contact_points(turned_plan, -1, obj)
    np.testing.assert_array_equal(pts, analysis.contacts(turned_plan, -1, obj=obj).points)
    assert len(pts) > 10
    assert np.abs(obj.signed_distance(pts)).max() < 1e-9  # marked on the object's surface
    # each mark is within reach of the hand: the link radius and 1 mm from some link axis or the palm
    j = turned_plan.joints[-1]
    a, b = j[:, :-1].reshape(-1, 3), j[:, 1:].reshape(-1, 3)
    ab = b - a
    t = np.clip(np.einsum("pkc,kc->pk", pts[:, None] - a[None], ab) / np.einsum("kc,kc->k", ab, ab), 0, 1)
    d_link = np.linalg.norm(pts[:, None] - (a[None] + t[..., None] * ab[None]), axis=2).min(axis=1)
    pose = turned_plan.palm_pose[-1]
    local = (pts - pose[:3, 3]) @ pose[:3, :3]  # in the palm frame: front face at z = 0
    near_palm = (np.hypot(local[:, 0], local[:, 1]) <= turned_plan.hand["palm_radius"]) & (
        np.abs(local[:, 2]) <= viz.CONTACT_DISTANCE)
    r = turned_plan.hand["link_radius"]
    near_link = d_link <= r + viz.CONTACT_DISTANCE + 1e-6
    assert np.all(near_link | near_palm) and near_palm.sum() >= 1


def test_contacts_come_from_the_analysis_module_when_present(turned_plan):
    analysis = pytest.importorskip("hugger.analysis", reason="hugger.analysis is not in this checkout")
    obj = turned_plan.object()
    expected = analysis.contacts(turned_plan, len(turned_plan) - 1).points
    assert np.array_equal(viz._contact_points(turned_plan, len(turned_plan) - 1, obj), expected)


# --- TipState plot ------------------------------------------------------------------------------------------

@needs_mpl
def test_tipstate_plot_shows_states_phase_and_contacts(turned_plan, tmp_path):
    fig = viz.tipstate_plot(turned_plan, tmp_path / "tip.png", dpi=60)
    _assert_a_picture(_read_png(tmp_path / "tip.png", viz.TIPSTATE_SIZE, 60))
    top, bottom = fig.axes[:2]
    assert np.array_equal(np.asarray(top.images[0].get_array()), turned_plan.tip_state.T)
    p2 = int(np.flatnonzero(turned_plan.phase == 2)[0])
    xs = {round(float(line.get_xdata()[0]), 3) for line in top.lines}
    assert p2 - 0.5 in xs  # the phase boundary is marked
    (count,) = [line for line in bottom.lines if "links within" in str(line.get_label())]
    assert count.get_xdata()[0] == 0 and count.get_xdata()[-1] == len(turned_plan) - 1
    assert count.get_ydata()[0] == 0
    assert count.get_ydata()[-1] == turned_plan.summary()["links_in_contact"]


@needs_mpl
def test_tipstate_plot_subsamples_long_plans(turned_plan):
    fig = viz.tipstate_plot(turned_plan, max_samples=25)
    (count,) = [line for line in fig.axes[1].lines if "links within" in str(line.get_label())]
    x = count.get_xdata()
    assert len(x) == 25 and x[0] == 0 and x[-1] == len(turned_plan) - 1 and np.all(np.diff(x) > 0)


# --- animation ------------------------------------------------------------------------------------------------

@needs_mpl
def test_animate_gif_has_the_expected_frames(small_plan, tmp_path):
    from PIL import Image

    calls = []
    n = viz.animate(small_plan, tmp_path / "movie" / "plan.gif", fps=8, max_frames=7,
                    progress=lambda i, total: calls.append((i, total)))
    assert n == 7 and calls == [(i, 7) for i in range(1, 8)]
    with Image.open(tmp_path / "movie" / "plan.gif") as im:
        assert im.n_frames == 7
        assert im.size == (round(viz.MOVIE_SIZE[0] * 100), round(viz.MOVIE_SIZE[1] * 100))
        assert im.info["duration"] == pytest.approx(125, abs=10)
        im.seek(3)
        _assert_a_picture(np.asarray(im.convert("RGB")))


@needs_mpl
def test_animate_short_plan_gives_one_frame_per_configuration(turned_plan, tmp_path):
    from PIL import Image

    traj = _first(turned_plan, 5)
    assert viz.render(traj, tmp_path / "short.gif", max_frames=300, dpi=40, max_faces=300) == tmp_path / "short.gif"
    with Image.open(tmp_path / "short.gif") as im:
        assert im.n_frames == len(traj) == 5


@needs_mpl
def test_ctrl_c_at_a_terminal_while_ffmpeg_writes_is_an_interrupt(tmp_path):
    # A terminal's Ctrl-C reaches the whole process group: ffmpeg ends first, and the render is
    # still an interrupt (130, nothing under the final name), not an internal error.
    import signal
    import time

    if viz.ffmpeg_path() is None:
        pytest.skip("no ffmpeg: pip install imageio-ffmpeg (or put ffmpeg on the PATH) to test MP4 output")
    c = hugger.scenarios.default_case("curvy")
    plan = tmp_path / "plan.npz"
    hugger.plan(c.hand, c.obj, c.target, c.palm_pose).save(plan)
    out = tmp_path / "plan.mp4"
    p = subprocess.Popen([sys.executable, "-m", "hugger", "render", str(plan), "--out", str(out), "--fps", "2"],
                         start_new_session=True, stderr=subprocess.PIPE, text=True)
    try:
        # ffmpeg runs once it has made its output, the temporary file beside the final name
        deadline = time.monotonic() + 120
        while (not list(tmp_path.glob(".plan.mp4.*")) and p.poll() is None
               and time.monotonic() < deadline):
            time.sleep(0.05)
        if p.poll() is not None:
            pytest.fail(f"the render ended before it was interrupted (status {p.returncode}): "
                        f"{p.communicate()[1]}")
        assert list(tmp_path.glob(".plan.mp4.*")), "ffmpeg made no output within 120 s"
        time.sleep(0.5)
        os.killpg(p.pid, signal.SIGINT)
        _, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
            p.communicate()
    assert p.returncode == 130 and err.strip() == "hugger: interrupted", err
    assert not out.exists()


@needs_mpl
def test_animate_mp4(small_plan, tmp_path):
    if viz.ffmpeg_path() is None:
        pytest.skip("no ffmpeg: pip install imageio-ffmpeg (or put ffmpeg on the PATH) to test MP4 output")
    out = tmp_path / "plan.mp4"
    assert viz.animate(small_plan, out, fps=10, max_frames=6, dpi=50) == 6
    data = out.read_bytes()
    assert data[4:8] == b"ftyp"
    try:
        import imageio_ffmpeg
    except ImportError:
        return
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(str(out))
    assert frames == 6 and seconds == pytest.approx(0.6, abs=0.05)


def test_the_headline_gives_unequal_links_as_a_range():
    # it gave their mean, a length no link of the hand has
    from hugger.viz.figures import _headline

    class Plan:
        object_faces = np.zeros((12, 3))
        status = "done"

        def __init__(self, lengths):
            self.hand = {"fingers": 3, "links": 2, "link_lengths": lengths, "link_radius": 0.004}

        def __len__(self):
            return 5

    assert "3 fingers x 2 links (20-30 mm, radius 4.0 mm), 12 triangles, 5 configurations" in \
        _headline(Plan([[0.02, 0.03]] * 3))
    assert "(20 mm, radius" in _headline(Plan([[0.02, 0.02]] * 3))


def test_ffmpeg_s_complaint_of_a_cut_frame_is_not_shown_on_ctrl_c(caplog):
    # ffmpeg, stopped by the terminal's Ctrl-C in the middle of a frame, complains of it, and
    # matplotlib logged that as a warning under "hugger: interrupted" (once in a few runs of the
    # test above); its output is shown when it failed on its own
    import logging
    import subprocess

    from hugger.viz.animation import _ffmpeg_interrupted

    log = logging.getLogger("matplotlib.animation")

    def writer_fails(after_interrupt: bool):
        with _ffmpeg_interrupted():
            try:
                if after_interrupt:
                    raise KeyboardInterrupt
                raise OSError("no interrupt")
            except (KeyboardInterrupt, OSError):
                log.warning("MovieWriter stderr:\n%s", "Invalid buffer size, packet size 851968")
                raise subprocess.CalledProcessError(255, ["ffmpeg"]) from None

    caplog.set_level(logging.WARNING, logger="matplotlib.animation")
    with pytest.raises(KeyboardInterrupt):
        writer_fails(True)
    assert "MovieWriter" not in caplog.text
    with pytest.raises(subprocess.CalledProcessError):
        writer_fails(False)
    assert "MovieWriter stderr:\nInvalid buffer size" in caplog.text
