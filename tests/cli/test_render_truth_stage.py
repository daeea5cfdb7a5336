"""``station render --engine truth`` on a stage (backdrop, ground, turned environment, clear coat), each a
real subprocess run from a temporary folder: its frame against the NumPy engine's frame of the same scene
(a separate implementation: prefiltered lobe maps against the designed BRDF's quadrature), the sun's
ray-cast shadow on the misaligned panels against a hand calculation of the sun's Lambert share under the
coat, its flakes' sparkle against the NumPy engine's, and the combinations the truth engine still refuses (exit 2, one line naming the field)."""

from __future__ import annotations

import json
import math
import subprocess
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage

from station.model import FaceFlopTravelGloss
from station.model.colorimetry import linear_srgb_to_lab
from station.model.design_io import save_design
from station.model.difference import delta_e
from station.render import procedural
from station.render.hdr_io import write_exr, write_hdr
from station.render.numpy_renderer import gbuffer
from station.render.shapes import Scene, ray_cast_visibility
from station.render.stage import Stage
from tests.render._fresnel_hand import diffuse_transmission, fresnel
from tests.user_cli import run_station

SIZE = 48
TURN = 37.0  # degrees, the stage's turn of the environment
MISALIGN = -30.0  # the right panel turned towards the camera: it shadows the left one from the right
COAT = 1.5
SKY, SUN, SUN_DEG = 0.25, 1000.0, 1.5  # a uniform sky and a sun disc of that radius (radiance)
SUN_WORLD = np.array(
    [math.sin(math.radians(70.0)), math.tan(math.radians(30.0)), math.cos(math.radians(70.0))]
)
SUN_WORLD /= np.linalg.norm(SUN_WORLD)  # azimuth 70° from +z towards +x, 30° above the horizon


def station(cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return run_station(cwd, *args)


def _turn(deg: float) -> np.ndarray:
    """R_y(deg): a map feature at direction e shows in the world at R_y(θ) e (the stage's turn), by hand."""
    a = math.radians(deg)
    return np.array([[math.cos(a), 0.0, math.sin(a)], [0.0, 1.0, 0.0], [-math.sin(a), 0.0, math.cos(a)]])


def _map_directions(h: int) -> tuple[np.ndarray, np.ndarray]:
    """Pixel-centre directions (h, 2h, 3) and solid angles (h, 2h) of an equirect map (+Y up, θ down the
    rows, φ = 2π(u − ½), direction (sin θ sin φ, cos θ, −sin θ cos φ)), by hand."""
    theta = math.pi * (np.arange(h) + 0.5) / h
    phi = 2.0 * math.pi * ((np.arange(2 * h) + 0.5) / (2 * h) - 0.5)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    dirs = np.stack([np.sin(t) * np.sin(p), np.cos(t), -np.sin(t) * np.cos(p)], -1)
    edges = math.pi * np.arange(h + 1) / h
    band = 2.0 * math.pi * (np.cos(edges[:-1]) - np.cos(edges[1:])) / (2 * h)
    return dirs, np.repeat(band[:, None], 2 * h, axis=1)


def _render(cwd: Path, name: str, *args: str) -> tuple[np.ndarray, dict]:
    res = station(
        cwd,
        "render",
        *args,
        "--size",
        str(SIZE),
        "--out",
        f"{name}.png",
        "--linear-out",
        f"{name}.npy",
        "--cache-dir",
        "prefiltered",
        "--json",
    )
    assert res.returncode == 0, res.stderr
    assert (cwd / f"{name}.png").is_file()
    return np.load(cwd / f"{name}.npy").astype(float), json.loads(res.stdout)


def test_truth_on_a_turned_coated_stage_agrees_with_the_numpy_engine(tmp_path: Path) -> None:
    """A metallic on the misaligned panels in a sunny sky, stage turned 37°, coat 1.5: the truth's frame and
    the NumPy engine's agree within CIEDE2000 0.3 at the 95th percentile (0.5 max) and 2 % in luminance over
    the panels' pixels 2 pixels and more from the sun's shadow outline (the sun's direction taken from the
    map's brightest pixel), and the backdrop and ground are the NumPy engine's, value for value."""
    save_design(FaceFlopTravelGloss((60.0, 10.0, -40.0), (30.0, 5.0, -30.0), 60.0, 85.0), tmp_path / "m.json")
    sky = procedural.sunny_sky(64).equirect
    write_hdr(tmp_path / "sky.hdr", sky)
    scene_args = [
        "--design",
        "m.json",
        "--env",
        "sky.hdr",
        "--shape",
        "panels",
        "--misalignment",
        str(MISALIGN),
    ]
    stage_args = ["--stage", "--rotate", str(TURN), "--coat", str(COAT)]
    truth, report = _render(tmp_path, "truth", *scene_args, *stage_args, "--engine", "truth")
    frame, _ = _render(tmp_path, "numpy", *scene_args, *stage_args, "--engine", "numpy")
    assert report["engine"] == "truth" and report["stage"] is True and report["coat_index"] == COAT

    scene = Scene("panels", MISALIGN, stage=Stage(rotation_deg=TURN))
    g = gbuffer(scene, SIZE, SIZE)
    lum = sky @ np.array([0.2126, 0.7152, 0.0722])
    sun = _turn(TURN) @ _map_directions(sky.shape[0])[0][np.unravel_index(np.argmax(lum), lum.shape)]
    dark = np.zeros((SIZE, SIZE), bool)
    dark[g.mask] = ray_cast_visibility(scene, g.position[g.mask], g.normal[g.mask], sun[None])[:, 0] == 0.0
    dark &= np.sum(g.normal * sun, axis=-1) > 0.0  # shadowed where the sun would light the panel
    outline = ndimage.binary_dilation(dark, iterations=2) & ~ndimage.binary_erosion(dark, iterations=2)
    judged = g.mask & ~outline
    assert dark.sum() > 20 and judged.sum() > 0.8 * g.mask.sum()

    white = float(truth[g.mask, 1].max())
    de = delta_e(
        linear_srgb_to_lab(truth[judged] / white), linear_srgb_to_lab(frame[judged] / white), "cie2000"
    )
    y = np.array([0.2126, 0.7152, 0.0722])
    rel = np.abs(frame[judged] @ y / (truth[judged] @ y) - 1.0)
    assert float(np.percentile(de, 95)) < 0.3 and float(de.max()) < 0.5
    assert float(rel.max()) < 0.02
    assert np.array_equal(truth[~g.mask], frame[~g.mask])  # the NumPy engine's backdrop and ground
    assert np.ptp(truth[~g.mask, 1]) > 0.1  # the backdrop shows the environment, not the flat grey


def test_truth_shadows_the_sun_by_the_ray_cast_on_a_turned_stage(tmp_path: Path) -> None:
    """A grey solid (L* 60: ρ = (76/116)³, no gloss where the sun is) on the panels under a uniform sky and
    a 1.5° sun, stage turned 37°, coat 1.5. Turned 30° towards the camera, the right panel hides the sun
    from part of the left one; flat (0°) it hides nothing, and the left panel's pixels are the same. Where
    the ray cast says the sun is hidden (2 pixels and more inside the shadow), the left panel is darker
    than flat by the sun's share, by hand: Σ_j (1 − F(N·V)) ρ t(N·l_j) (N·l_j) Φ_j/π over the sun's map
    pixels j (flux Φ_j = (L_sun − L_sky) Ω_j, t = (1 − F(N·l))/(1 − F_dr,ext)), to 1e-4; elsewhere it
    is the flat frame to 1e-9."""
    grey = 60.0
    save_design(
        FaceFlopTravelGloss((grey, 0.0, 0.0), (grey, 0.0, 0.0), None, 60.0, "grey"), tmp_path / "g.json"
    )
    h = 128
    dirs, omega = _map_directions(h)
    sun_map = (
        _turn(TURN).T @ SUN_WORLD
    )  # where the map holds the sun so that the turned stage shows it at SUN_WORLD
    disc = dirs @ sun_map > math.cos(math.radians(SUN_DEG))
    eq = np.full((h, 2 * h, 3), SKY, np.float32)
    eq[disc] = SUN
    write_exr(tmp_path / "sun.exr", eq)
    args = ["--design", "g.json", "--env", "sun.exr", "--shape", "panels", "--stage", "--rotate", str(TURN)]
    args += ["--coat", str(COAT), "--engine", "truth"]
    shadowed, _ = _render(tmp_path, "shadowed", *args, "--misalignment", str(MISALIGN))
    flat, _ = _render(tmp_path, "flat", *args, "--misalignment", "0")

    scene = Scene("panels", MISALIGN, stage=Stage(rotation_deg=TURN))
    g = gbuffer(scene, SIZE, SIZE)
    left = g.mask & (g.paint == 0)
    assert np.array_equal(left, gbuffer(Scene("panels", 0.0), SIZE, SIZE).paint == 0)
    hidden = np.zeros((SIZE, SIZE), bool)
    hidden[left] = ray_cast_visibility(scene, g.position[left], g.normal[left], SUN_WORLD[None])[:, 0] == 0.0
    inside = ndimage.binary_erosion(hidden, iterations=2)
    lit = left & ~ndimage.binary_dilation(hidden, iterations=2)
    assert inside.sum() > 30 and lit.sum() > 200

    lights = _turn(TURN) @ dirs[disc].T  # (3, k) the sun's pixels in the world
    n_dot_l = lights[2]  # the left panel faces +z
    assert n_dot_l.min() > 0.2
    flux = (SUN - SKY) * omega[disc]
    rho = ((grey + 16.0) / 116.0) ** 3
    entry = (1.0 - fresnel(n_dot_l, COAT)) / diffuse_transmission(COAT)
    share = rho * float(np.sum(entry * n_dot_l * flux)) / math.pi
    eye = np.array(scene.view_camera.eye)
    n_dot_v = (eye[2] - g.position[inside][:, 2]) / np.linalg.norm(eye - g.position[inside], axis=-1)
    view = (eye - g.position[inside]) / np.linalg.norm(eye - g.position[inside], axis=-1, keepdims=True)
    mirror = 2.0 * n_dot_v[:, None] * np.array([0.0, 0.0, 1.0]) - view
    assert np.degrees(np.arccos((mirror @ lights).max())) > 40.0  # the gloss lobe (n ≈ 520) sees no sun
    expected = (1.0 - fresnel(n_dot_v, COAT)) * share
    lost = flat[inside] - shadowed[inside]
    assert lost == pytest.approx(np.repeat(expected[:, None], 3, axis=1), rel=1e-4)
    assert shadowed[lit] == pytest.approx(flat[lit], rel=1e-9)
    assert np.all(lost[:, 1] > 0.3 * flat[inside, 1])  # the sun is a large share: the shadow is seen


def test_truth_flakes_on_a_turned_stage_follow_the_numpy_engine(tmp_path: Path) -> None:
    """A close-up of the metallic on the panels (27 flakes per pixel: the level of detail keeps them on),
    stage turned 37°, coat 1.5: the truth engine's sparkle (its frame with the flake layer minus without)
    follows the NumPy engine's pixel by pixel (correlation above 0.95 in G, RMS difference below 30 % of
    the sparkle's RMS; the NumPy engine reads the sharpest prefiltered map and a lobe-map mean where the
    truth reads the full map and the exact mean) and averages to nothing (zero mean: the colour is kept)."""
    save_design(FaceFlopTravelGloss((60.0, 10.0, -40.0), (30.0, 5.0, -30.0), 60.0, 85.0), tmp_path / "m.json")
    write_hdr(tmp_path / "sky.hdr", procedural.sunny_sky(64).equirect)
    args = ["--design", "m.json", "--env", "sky.hdr", "--shape", "panels", "--misalignment", str(MISALIGN)]
    args += ["--view", "0,10,0.5", "--stage", "--rotate", str(TURN), "--coat", str(COAT)]
    layer = ["--flake-size", "30", "--flake-density", "60", "--flake-spread", "8"]
    sparkle = {}
    for engine in ("truth", "numpy"):
        on, report = _render(tmp_path, f"{engine}-on", *args, *layer, "--engine", engine)
        off, _ = _render(tmp_path, f"{engine}-off", *args, "--engine", engine)
        assert report["flakes"].endswith(": on") and report["flake_layer"]["size_um"] == 30.0
        sparkle[engine] = (on - off).reshape(-1, 3)
    t, n = sparkle["truth"], sparkle["numpy"]
    shown = np.abs(t).sum(-1) > 0
    assert shown.sum() > 0.5 * SIZE * SIZE
    assert np.corrcoef(t[shown, 1], n[shown, 1])[0, 1] > 0.95
    assert np.sqrt(np.mean((t - n)[shown] ** 2)) < 0.3 * np.sqrt(np.mean(t[shown] ** 2))
    assert np.all(np.abs(t[shown].mean(axis=0)) < 0.1 * t[shown].std(axis=0))


@pytest.mark.parametrize(
    ("extra", "field"),
    [
        (["--lod", "1"], "lod"),
        (["--aa", "4"], "engine"),
        (["--mesh", "car"], "engine"),
    ],
)
def test_truth_refusals_exit_2_with_one_line(tmp_path: Path, extra: list[str], field: str) -> None:
    """What the truth engine does not draw (a level of detail, anti-aliasing, a mesh) is refused
    with exit 2 and one line naming the field and what is accepted."""
    save_design(FaceFlopTravelGloss((60.0, 10.0, -40.0), (30.0, 5.0, -30.0), 60.0, 85.0), tmp_path / "m.json")
    res = station(
        tmp_path,
        "render",
        "--design",
        "m.json",
        "--engine",
        "truth",
        "--stage",
        "--size",
        "16",
        "--out",
        "o.png",
        *extra,
    )
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and f"{field}: expected" in lines[0], res.stderr
    assert "gl" in lines[0]  # the engines that do draw it are named
    assert not (tmp_path / "o.png").exists()
