"""The 3D viewer (viser) in a real browser, and the glTF scene export (trimesh).

The browser test drives Debian's headless Chromium with the system chromedriver through
selenium (nothing is downloaded at run time); `make` installs both (APT_PACKAGES). Without
them the test is skipped with the reason.
"""
from __future__ import annotations

import io
import shutil
import socket
import subprocess
import sys
import time

import numpy as np
import pytest

import hugger
from hugger._rotation import quaternion_wxyz
from hugger import cli, viewer

from helpers import assert_names_the_extra, run_cli

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CHROMEDRIVER = shutil.which("chromedriver")


@pytest.fixture(scope="module")
def plans(tmp_path_factory):
    """Two short plans: the 5 x 5 hand on the sphere, and a 3 x 4 hand on the ellipsoid turned away."""
    d = tmp_path_factory.mktemp("viewer")
    a, b = d / "sphere.npz", d / "ellipsoid.npz"
    assert cli.main(["plan", "sphere", "--out", str(a)]) == 0
    assert cli.main(["plan", "ellipsoid", "--out", str(b), "--fingers", "3", "--links", "4", "--link-length", "0.025",
                     "--step", "0.002", "--turn", "30"]) == 0
    return a, b


# --- meshes -------------------------------------------------------------------------------------

@pytest.mark.parametrize("length, radius", [(0.02, 0.004), (0.031, 0.0005), (0.01, 0.01)])
def test_capsule_mesh_is_a_closed_outward_capsule(length, radius):
    trimesh = pytest.importorskip("trimesh")
    v, f = viewer.capsule_mesh(length, radius)
    mesh = trimesh.Trimesh(v, f, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    exact = np.pi * radius ** 2 * length + 4 / 3 * np.pi * radius ** 3
    assert mesh.volume == pytest.approx(exact, rel=0.08)  # a faceted capsule, a little smaller
    assert v[:, 2].min() == pytest.approx(-radius) and v[:, 2].max() == pytest.approx(length + radius)
    assert np.hypot(v[:, 0], v[:, 1]).max() == pytest.approx(radius)


def test_palm_mesh_is_the_palm_disc():
    trimesh = pytest.importorskip("trimesh")
    v, f = viewer.palm_mesh(0.03, 0.01)
    mesh = trimesh.Trimesh(v, f, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume == pytest.approx(np.pi * 0.03 ** 2 * 0.01, rel=0.01)
    assert v[:, 2].max() == 0.0 and v[:, 2].min() == -0.01  # front face at P_o


def test_link_frames_put_each_capsule_on_its_link(plans):
    rng = np.random.default_rng(3)
    for path in plans:
        traj = hugger.Trajectory.load(path)
        plan = viewer._Plan.of(traj)
        for k in rng.integers(0, len(traj), 5):
            frames = plan.link_frames(int(k))
            j = traj.joints[k]
            rot = frames[..., :3, :3]
            assert np.allclose(np.einsum("mnij,mnkj->mnik", rot, rot), np.eye(3), atol=1e-12)
            assert np.allclose(np.linalg.det(rot), 1.0)
            tip = frames[..., :3, 3] + rot[..., :, 2] * plan.lengths[..., None]
            assert np.allclose(frames[..., :3, 3], j[:, :-1]) and np.allclose(tip, j[:, 1:], atol=1e-9)
            for m in range(plan.fingers):  # the quaternion is the rotation
                q = quaternion_wxyz(rot[m, 0])
                w, x, y, z = q
                r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                              [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                              [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
                assert np.allclose(r, rot[m, 0], atol=1e-12)


# --- glTF export ----------------------------------------------------------------------------------

def test_export_scene_final_grasp_loads_in_trimesh(plans, tmp_path, capsys):
    trimesh = pytest.importorskip("trimesh")
    traj = hugger.Trajectory.load(plans[0])
    out = tmp_path / "grasp.glb"
    code, text, err = run_cli(["export-scene", plans[0], "--out", out], capsys)
    assert code == 0, err
    scene = trimesh.load(out)
    contacts = len(hugger.analysis.contacts(traj, -1))
    assert contacts > 0
    expected = 2 + 1 + 25 + 1  # object, target, palm, 5 x 5 links, the contacts
    assert len(scene.graph.nodes_geometry) == expected and f"{expected} meshes" in text
    names = set(scene.graph.nodes_geometry)
    assert {"object", "target", "palm", "contacts"} | {f"f{m}_l{n}" for m in range(5) for n in range(5)} <= names
    # the final palm and a fingertip where the plan has them
    palm, _ = scene.graph["palm"]
    assert np.allclose(palm, traj.palm_pose[-1], atol=1e-6)
    tip, geom = scene.graph["f2_l4"]
    link = scene.geometry[geom]
    far = tip @ np.array([0.0, 0.0, 0.02, 1.0])
    assert np.allclose(far[:3], traj.joints[-1, 2, 5], atol=1e-6)
    assert np.ptp(link.vertices[:, 2]) == pytest.approx(0.02 + 2 * 0.004, rel=1e-6)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["grasp.glb"]
    # glTF materials: the object blended at alpha 0.5 (a vertex colour's alpha alone is ignored,
    # the default mode being opaque), the hand opaque; and normals, for smooth shading
    obj = scene.geometry[scene.graph["object"][1]].visual.material
    assert obj.alphaMode == "BLEND" and obj.baseColorFactor[3] == 128
    assert link.visual.material.alphaMode == "OPAQUE" and link.visual.material.baseColorFactor[3] == 255
    import json
    import struct

    data = out.read_bytes()
    gltf = json.loads(data[20:20 + struct.unpack("<I", data[12:16])[0]])
    assert all("NORMAL" in p["attributes"] for mesh in gltf["meshes"] for p in mesh["primitives"])


def test_export_scene_all_frames(plans, tmp_path, capsys):
    trimesh = pytest.importorskip("trimesh")
    traj = hugger.Trajectory.load(plans[1])  # 3 x 4 hand, with a Phase 1
    out = tmp_path / "all.glb"
    code, _, err = run_cli(["export-scene", plans[1], "--out", out, "--all"], capsys)
    assert code == 0, err
    scene = trimesh.load(out)
    with_contacts = sum(len(hugger.analysis.contacts(traj, k)) > 0 for k in range(len(traj)))
    assert len(scene.graph.nodes_geometry) == 2 + len(traj) * (1 + 3 * 4) + with_contacts
    assert f"k{len(traj) - 1}/f2_l3" in scene.graph.nodes_geometry
    # identical links are stored once: a few meshes (length x TipState), not one per node
    assert len(scene.geometry) <= 2 + 1 + 3 + with_contacts


def test_export_scene_without_trimesh_names_the_extra(plans, tmp_path):
    assert_names_the_extra("trimesh", ["export-scene", plans[0], "--out", tmp_path / "x.glb"], "hugger[view]")


def test_view_without_viser_names_the_extra(plans):
    assert_names_the_extra("viser", ["view", plans[0], "--no-browser"], "hugger[view]")


# --- the viewer, server side ------------------------------------------------------------------------

def test_viewer_scene_timeline_and_toggles(plans):
    pytest.importorskip("viser")
    trajs = [hugger.Trajectory.load(p) for p in plans]
    with viewer.view(trajs, port=0, open_browser=False, block=False) as v:
        scene = v.server.scene
        for i, t in enumerate(trajs):
            m, n = t.hand["fingers"], t.hand["links"]
            names = viewer.scene_nodes(m, n, i)
            assert len(names["links"]) == m * n == len(v.links[i])
            for name in sum(names.values(), []):
                assert scene.get_handle_by_name(name) is not None, name
        assert v.count == max(len(t) for t in trajs) and v.configuration == v.count - 1
        assert v.offsets[1][0] > v.offsets[0][0]  # side by side
        for k in (0, len(trajs[0]) // 2, v.count - 1):
            v.show(k)
            for i, t in enumerate(trajs):
                kk = min(k, len(t) - 1)
                assert np.allclose(v.palms[i].position, t.palm_pose[kk, :3, 3])
                for m in range(t.hand["fingers"]):
                    h = v.links[i][m * t.hand["links"]]
                    assert np.allclose(h.position, t.joints[kk, m, 0])
                    assert tuple(h.color) == viewer.STATE_RGB[int(t.tip_state[kk, m])]
                assert v.contact_clouds[i].visible == (len(hugger.analysis.contacts(t, kk)) > 0)
        assert int(v.slider.value) == v.count - 1
        v.transparent.value = False
        v._set_opacity()
        assert v.objects[0].opacity is None
        v.show_contacts.value = False
        v.show(v.count - 1)
        assert not v.contact_clouds[0].visible
        # play runs from C_init and pauses on the final grasp
        v.fps = 200.0
        v._toggle()
        assert v.playing and v.configuration == 0
        deadline = time.time() + 30
        while v.playing and time.time() < deadline:
            time.sleep(0.05)
        assert not v.playing and v.configuration == v.count - 1
        with pytest.raises(ValueError, match="k must be in"):
            v.show(v.count)
    with viewer.view(str(plans[0]), port=0, open_browser=False, block=False) as v:  # a file's path
        assert len(v.plans) == 1 and len(v.links[0]) == 25
    with pytest.raises(ValueError, match="the viewer is closed"):  # (viser only warned)
        v.show(0)
    with pytest.raises(ValueError, match="at least one"):
        viewer.Viewer([])
    with pytest.raises(ValueError, match="port"):
        viewer.Viewer(trajs, port=-1)


# --- the viewer in a real browser -------------------------------------------------------------------

def _screenshot(driver) -> np.ndarray:
    from PIL import Image

    with Image.open(io.BytesIO(driver.get_screenshot_as_png())) as im:
        return np.asarray(im.convert("RGB"), dtype=np.int64)


needs_chromium = pytest.mark.skipif(
    CHROMIUM is None or CHROMEDRIVER is None,
    reason="needs Debian's chromium and chromium-driver (apt-get install chromium chromium-driver; make installs them)")


@pytest.fixture(scope="module")
def browser():
    """Headless Chromium (the system's) under the system chromedriver, one for this module's tests."""
    webdriver = pytest.importorskip("selenium.webdriver")
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    options = Options()
    options.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--window-size=800,600",
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    driver.set_page_load_timeout(60)
    yield driver
    driver.quit()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@needs_chromium
def test_viewer_in_headless_chromium(plans, tmp_path, browser):
    pytest.importorskip("viser")
    from PIL import Image

    port = _free_port()
    # the command itself, as a user runs it
    proc = subprocess.Popen([sys.executable, "-m", "hugger", "view", str(plans[0]), str(plans[1]), "--no-browser",
                             "--port", str(port)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    driver = browser
    try:
        line = proc.stdout.readline()
        assert f"at http://localhost:{port}" in line, (line, proc.stderr.read() if proc.poll() is not None else "")
        driver.get(f"http://localhost:{port}")
        # the scene is drawn on a WebGL canvas, the controls are the GUI panel
        deadline = time.time() + 60
        while time.time() < deadline:
            ready = driver.execute_script(
                "return Array.from(document.querySelectorAll('canvas')).some(c => c.width > 0) &&"
                " document.body.innerText.includes('plan 1: k = ');")
            if ready:
                break
            time.sleep(0.5)
        assert ready, driver.page_source[:500]
        text = driver.execute_script("return document.body.innerText")
        assert "configuration k" in text and "play / pause" in text and "transparent object" in text
        time.sleep(4.0)  # let the meshes arrive and draw
        png = tmp_path / "view.png"
        driver.save_screenshot(str(png))
        with Image.open(png) as im:
            rgb = np.asarray(im.convert("RGB"), dtype=np.int64)
        # not blank, and the grasps are there: DONE-green link pixels and grey palm pixels
        assert rgb.std() > 10
        r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
        green = (g > r + 30) & (g > b + 20)
        assert green.sum() > 200, green.sum()
        colours = len(np.unique(rgb.reshape(-1, 3) // 8, axis=0))
        assert colours > 50, colours
    finally:
        proc.terminate()
        try:
            proc.communicate(timeout=10)  # also closes the pipes
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()


@needs_chromium
def test_viewer_page_has_every_link_mesh(plans, tmp_path, browser):
    """The page connects and receives the scene: M x N link meshes per plan in the scene the viser
    server sends every client, and the page redraws when the timeline moves."""
    pytest.importorskip("viser")
    trajs = [hugger.Trajectory.load(p) for p in plans]
    with viewer.view(trajs, port=_free_port(), open_browser=False, block=False) as v:
        driver = browser
        try:
            driver.get(v.url)
            deadline = time.time() + 60
            while not v.server.get_clients() and time.time() < deadline:
                time.sleep(0.25)
            clients = v.server.get_clients()
            assert len(clients) == 1
            link_nodes = [name for name in v.server.scene._handle_from_node_name if "/links/" in name]
            assert len(link_nodes) == sum(t.hand["fingers"] * t.hand["links"] for t in trajs) == 25 + 12
            # the page follows the timeline: the final grasp and C_init look different
            time.sleep(3.0)
            final = _screenshot(driver)
            v.show(0)
            time.sleep(3.0)
            start = _screenshot(driver)
            changed = np.any(np.abs(final - start) > 40, axis=2)
            assert changed.mean() > 0.003, changed.mean()
        finally:
            driver.get("about:blank")  # leave the page before its server stops


def test_view_command_serves_until_interrupted(plans, monkeypatch, capsys):
    pytest.importorskip("viser")
    seen = []

    def wait(v):  # what Ctrl-C does to the command
        seen.append(v.server.scene.get_handle_by_name("/plan0/links/f4_l4") is not None)
        raise KeyboardInterrupt

    monkeypatch.setattr(viewer, "_serve", wait)
    code = cli.main(["view", str(plans[0]), "--no-browser", "--port", "0"])
    out, _ = capsys.readouterr()
    assert code == 0 and "serving 1 plan at http://localhost:" in out and seen == [True]


def test_an_object_free_plan_is_refused_before_the_server_starts(tmp_path):
    pytest.importorskip("viser")
    c = hugger.scenarios.default_case("sphere")
    free = hugger.Planner(c.hand, hugger._core.SimulatedWorld(c.obj._core), c.target, c.palm_pose).plan()
    assert not free.has_object
    free.save(tmp_path / "free.npz")
    r = subprocess.run([sys.executable, "-m", "hugger", "view", str(tmp_path / "free.npz"), "--no-browser", "--port",
                        "0"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "object-free" in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "viser" not in r.stdout + r.stderr  # no server was started (nor stopped)


@pytest.mark.parametrize("host, message", [("8.8.8.8", "cannot serve on host '8.8.8.8'"),
                                           ("no.such.host.invalid", "cannot serve on host 'no.such.host.invalid'"),
                                           ("", "host must be")])
def test_a_host_no_server_can_listen_on_is_refused_at_once(sphere_plan, host, message):
    # viser would try port after port there, for ever
    t0 = time.perf_counter()
    with pytest.raises(ValueError, match=message):
        viewer.Viewer(sphere_plan, host=host)
    assert time.perf_counter() - t0 < 30
