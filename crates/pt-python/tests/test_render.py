"""Rendering from Python: the same image as `pt render`, bit for bit; the GIL released; Ctrl-C;
progress."""

import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import pt_renderer as pt
from conftest import run_pt


def bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


@pytest.mark.parametrize(
    "scene, options, cli",
    [
        # The default path tracer on the Cornell box.
        ("scenes/cornell-box.xml", dict(spp=8, seed=5), ["--spp", "8", "--seed", "5"]),
        # Another method by name (its defaults come from the same table as the CLI's).
        ("scenes/cornell-box.xml", dict(spp=2, seed=1, integrator="bdpt", max_depth=5),
         ["--spp", "2", "--seed", "1", "--integrator", "bdpt", "--max-depth", "5"]),
        # A spectral scene (automatic mode), and a scene with a wide filter (splatting film).
        ("scenes/cornell-spectral.xml", dict(spp=4, seed=2), ["--spp", "4", "--seed", "2"]),
        ("scenes/film-tent.xml", dict(spp=4, seed=9), ["--spp", "4", "--seed", "9"]),
    ],
)
def test_render_equals_the_cli_bit_for_bit(repo, pt_bin, tmp_path, scene, options, cli):
    """Every channel and the variance equal `pt render` of the same scene, seed and spp, bit for
    bit (the film's sums are exact, so thread counts do not matter: 1 thread here, 2 there)."""
    out = tmp_path / "cli.exr"
    run_pt(pt_bin, "render", repo / scene, "-o", out, "--variance", "--threads", "2", "--quiet", *cli)
    s = pt.load_file(repo / scene)
    planes, facts = pt.render_channels(s, threads=1, **options)
    cli_planes = pt.read_exr_channels(out)
    cli_var = pt.read_exr_channels(tmp_path / "cli_var.exr")
    assert set(cli_planes) == set(planes) - {"variance"}
    for name, plane in cli_planes.items():
        differ = int(np.count_nonzero(bits(plane) != bits(planes[name])))
        assert differ == 0, f"{scene}: channel {name}: {differ} values differ"
    for k, name in enumerate("RGB"):
        differ = int(np.count_nonzero(bits(cli_var[name]) != bits(planes["variance"][:, :, k])))
        assert differ == 0, f"{scene}: variance {name}: {differ} values differ"
    assert facts["spp"] == options["spp"]
    # render() returns the same numbers as an (H, W, C) array.
    image, var = pt.render(s, threads=1, variance=True, **options)
    assert image.dtype == np.float32 and image.shape[2] == len(cli_planes)
    names = [n for n in planes if n != "variance"]
    for k, name in enumerate(names):
        assert np.array_equal(bits(image[:, :, k]), bits(planes[name])), name
    assert np.array_equal(bits(var), bits(planes["variance"]))


def test_render_defaults_are_the_scenes(repo):
    """Without options: the scene's spp and seed; -D-style keyword parameters reach the file."""
    s = pt.cornell_box()
    info = s.info()
    assert (info["width"], info["height"], info["spp"]) == (256, 256, 64)
    small = pt.load_file(repo / "scenes/cornell-box.xml")
    assert small.info()["integrator"] == "Path"
    s2 = pt.load_string(
        (repo / "scenes/cornell-box.xml").read_text(), base_dir=repo / "scenes"
    )
    assert s2.info()["triangles"] == info["triangles"]


def test_gil_is_released_while_rendering():
    """Another Python thread keeps running during a render: with the GIL held it would not get
    a single turn until the render returned."""
    scene = pt.cornell_box()
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    time.sleep(0.05)
    start = time.perf_counter()
    pt.render(scene, spp=32, threads=1)
    end = time.perf_counter()
    stop.set()
    t.join()
    during = [x for x in ticks if start < x < end]
    # The render takes a few tenths of a second; a thread ticking every millisecond gets
    # dozens of turns if the GIL is free. Zero or one would mean it was held.
    assert end - start > 0.1, "the render was too short to tell"
    assert len(during) > 20, f"{len(during)} ticks in {end - start:.2f} s of rendering"


def test_progress_callback_reports_and_can_stop_the_render():
    calls = []
    pt.render(pt.cornell_box(), spp=16, threads=1, progress=lambda d, t, s: calls.append((d, t, s)))
    assert calls, "no progress reported"
    done = [d for d, _, _ in calls]
    assert done == sorted(done)
    assert calls[-1][0] == calls[-1][1] == 256 * 256 * 16
    assert {s for _, _, s in calls} == {"sampling"}

    class Stop(Exception):
        pass

    def stop(d, t, s):
        raise Stop()

    start = time.perf_counter()
    with pytest.raises(Stop):
        pt.render(pt.cornell_box(), spp=100000, threads=1, progress=stop)
    assert time.perf_counter() - start < 10


def test_ctrl_c_raises_keyboard_interrupt_promptly(tmp_path):
    """SIGINT during a long render (about half an hour at this spp on one thread) raises
    KeyboardInterrupt within a few seconds: the render stops after its current pass."""
    script = tmp_path / "long_render.py"
    # A shell starts background jobs with SIGINT ignored, and Python then keeps it ignored: CI
    # runs this suite that way. The child puts back Python's own handler, as an interactive
    # session (a terminal, a Jupyter kernel) has it.
    script.write_text(textwrap.dedent("""
        import signal, sys, time
        signal.signal(signal.SIGINT, signal.default_int_handler)
        import pt_renderer as pt
        scene = pt.cornell_box()
        print("start", flush=True)
        try:
            pt.render(scene, spp=100000, threads=1)
        except KeyboardInterrupt:
            print("interrupted", time.perf_counter(), flush=True)
            sys.exit(0)
        print("finished", flush=True)
        sys.exit(1)
    """))
    p = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "start"
        time.sleep(1.0)
        sent = time.perf_counter()
        p.send_signal(subprocess.signal.SIGINT)
        out, _ = p.communicate(timeout=30)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 0, out
    word, when = out.split()
    assert word == "interrupted"
    # perf_counter is system-wide on Linux (CLOCK_MONOTONIC), so the two processes' readings
    # compare. A pass lasts about a second; 5 s leaves room for a loaded CI machine.
    assert float(when) - sent < 5.0


def test_bad_options_are_python_errors(repo):
    s = pt.cornell_box()
    with pytest.raises(ValueError, match="unknown integrator 'pth'"):
        pt.render(s, integrator="pth")
    with pytest.raises(ValueError, match="spp must be at least 1"):
        pt.render(s, spp=0)
    with pytest.raises(ValueError, match="mode must be 'rgb' or 'spectral'"):
        pt.render(s, spp=1, mode="hsv")
    with pytest.raises(ValueError, match="threads must be at least 1"):
        pt.render(s, spp=1, threads=0)
    with pytest.raises(TypeError, match="render needs a Scene"):
        pt.render(str(repo / "scenes/cornell-box.xml"))
    # A setting the chosen method does not have is refused with the CLI's message.
    with pytest.raises(pt.SceneError):
        pt.render(s, spp=1, integrator="radiosity", max_depth=3)
