"""pt from Python: render scenes, compare images and evaluate BSDFs, numpy arrays in and out.

pt is a physically based renderer checked against Mitsuba 3. This module calls the library the
``pt`` command line calls, with the same defaults: a render from here equals ``pt render`` of
the same scene, seed and sample count bit for bit.

>>> import pt_renderer as pt
>>> scene = pt.load_file("scenes/cornell-box.xml", spp=16)   # -D spp=16
>>> image = pt.render(scene, seed=1)                          # (H, W, 3) float32, linear sRGB

Conventions:

- Images are float32 arrays (H, W, C), row 0 at the top, linear (no tone mapping).
- BSDF directions are in the local shading frame (z along the normal), both pointing away from
  the surface: ``wo`` towards the viewer, ``wi`` towards the light. Wavelengths in nm.
- Errors are exceptions: a scene, BSDF or option pt refuses raises :class:`SceneError` (a
  ``ValueError``) whose message names the file, line, column and element; a missing scene file
  raises ``FileNotFoundError``; an unreadable image ``OSError``.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _pt_renderer as _core
from ._pt_renderer import Scene, SceneError

__all__ = [
    "Bsdf",
    "Scene",
    "SceneError",
    "METHODS",
    "__version__",
    "load_file",
    "load_string",
    "cornell_box",
    "render",
    "render_channels",
    "read_exr",
    "read_exr_channels",
    "write_exr",
    "compare",
    "bsdf",
    "bsdf_models",
    "converge",
]

__version__: str = _core.VERSION
#: Light transport methods ``render(integrator=...)`` accepts.
METHODS: Tuple[str, ...] = tuple(_core.METHODS)

PathLike = Union[str, "os.PathLike[str]"]
#: ``progress(done, total, stage)``: samples taken of ``total`` while sampling (stage
#: ``"sampling"``), or thousandths of a staged method's (radiosity's) stage.
ProgressCallback = Callable[[int, int, str], Any]


def _defines(params: Mapping[str, Any]) -> List[Tuple[str, str]]:
    """Scene parameters as Mitsuba's ``-D name=value`` strings (``True`` -> ``true``)."""
    out = []
    for name, value in params.items():
        if isinstance(value, bool):
            value = "true" if value else "false"
        out.append((str(name), str(value)))
    return out


def _existing_file(path: PathLike) -> Path:
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(errno.ENOENT, os.strerror(errno.ENOENT), str(p))
    return p


def load_file(path: PathLike, camera: Optional[int] = None, **params: Any) -> Scene:
    """Loads a Mitsuba 3 XML scene (or a glTF 2.0 file, by its ``.gltf`` / ``.glb`` extension).

    Keyword arguments set the scene's ``<default>`` parameters, as Mitsuba's
    ``mi.load_file(path, spp=64)`` and the command line's ``-D spp=64`` do. ``camera`` picks a
    glTF file's camera (0-based).

    Raises ``FileNotFoundError`` when ``path`` does not exist, :class:`SceneError` when the
    scene (or a file it names) is refused, with the file, line and element in the message.
    """
    return _core.load_file(str(_existing_file(path)), _defines(params), camera)


def load_string(xml: str, base_dir: PathLike = ".", **params: Any) -> Scene:
    """Loads a Mitsuba 3 XML scene from a string; relative file names in it (meshes, textures,
    includes) are taken from ``base_dir``. Keyword arguments as for :func:`load_file`."""
    return _core.load_string(xml, str(base_dir), _defines(params))


def cornell_box(**params: Any) -> Scene:
    """The built-in Cornell box (what ``pt render`` renders without a scene), with
    ``<default>`` parameters as keyword arguments."""
    return _core.load_file(None, _defines(params), None)


def render(
    scene: Scene,
    spp: Optional[int] = None,
    seed: Optional[int] = None,
    integrator: Optional[str] = None,
    threads: Optional[int] = None,
    mode: Optional[str] = None,
    max_depth: Optional[int] = None,
    variance: bool = False,
    progress: Optional[ProgressCallback] = None,
) -> Union[np.ndarray, Tuple[np.ndarray, np.ndarray]]:
    """Renders ``scene`` and returns the image as float32 (H, W, C).

    The channels are those ``pt render`` writes to its EXR, in its order: the film's
    ``pixel_format`` (``R, G, B`` by default; ``A`` with alpha; ``Y`` for luminance; ``X, Y, Z``)
    followed by an ``aov`` integrator's channels; :func:`render_channels` names them.

    - ``spp``, ``seed``: samples per pixel and seed [default: the scene's sampler].
    - ``integrator``: one of :data:`METHODS` [default: the scene's integrator]. Naming the
      scene's own method keeps its parameters.
    - ``threads``: worker threads [default: one per core]; the image does not depend on it.
    - ``mode``: ``"rgb"`` or ``"spectral"`` [default: spectral when the scene needs it].
    - ``max_depth``: longest path in segments (-1: unlimited) [default: the scene's].
    - ``variance``: also return the variance of each pixel's mean, float32 (H, W, 3), as
      ``pt render --variance`` writes it.
    - ``progress``: called about 20 times a second as ``progress(done, total, stage)``; if it
      raises, the render stops and the exception propagates.

    The GIL is released while rendering: other Python threads run. Ctrl-C stops the render
    within about a second (after the current pass) and raises ``KeyboardInterrupt``.
    """
    image, var, _names, _spp, _secs, warnings = _render(
        scene, spp, seed, integrator, threads, mode, max_depth, progress
    )
    _warn(warnings)
    return (image, var) if variance else image


def render_channels(scene: Scene, **options: Any) -> Tuple[Dict[str, np.ndarray], Dict[str, Any]]:
    """Renders like :func:`render` (same options, ``variance`` excepted) and returns every
    channel by name, each (H, W), plus ``variance`` (H, W, 3), and a dict of facts: ``spp``
    taken, ``seconds`` of sampling, ``warnings``."""
    args = [options.pop(k, None) for k in ("spp", "seed", "integrator", "threads", "mode", "max_depth", "progress")]
    if options:
        raise TypeError(f"unknown options: {', '.join(sorted(options))}")
    image, var, names, spp, secs, warnings = _render(scene, *args)
    planes = {n: image[:, :, k] for k, n in enumerate(names)}
    planes["variance"] = var
    return planes, {"spp": spp, "seconds": secs, "warnings": list(warnings)}


def _render(scene, spp, seed, integrator, threads, mode, max_depth, progress):
    if not isinstance(scene, Scene):
        raise TypeError(f"render needs a Scene (from load_file, load_string or cornell_box), not {type(scene).__name__}")
    return _core.render(scene, spp, seed, integrator, threads, mode, max_depth, progress)


def _warn(warnings: Sequence[str]) -> None:
    import warnings as _w

    for line in warnings:
        _w.warn(line, RuntimeWarning, stacklevel=3)


def read_exr(path: PathLike) -> np.ndarray:
    """Reads an OpenEXR image as ``pt compare`` does: float32 (H, W, 3) linear RGB (a
    luminance-only file's Y in all three). ``FileNotFoundError`` if missing, ``OSError`` if
    unreadable."""
    return _core.read_exr(str(_existing_file(path)))


def read_exr_channels(path: PathLike) -> Dict[str, np.ndarray]:
    """Every channel of an OpenEXR file by name (``"R"``, ``"G"``, ``"B"``, AOVs ...), each
    float32 (H, W), in the file's order."""
    return dict(_core.read_exr_channels(str(_existing_file(path))))


def write_exr(path: PathLike, image: np.ndarray, channels: Optional[Sequence[str]] = None) -> None:
    """Writes a float array (H, W), (H, W, 1), (H, W, 3) or (H, W, 4) as a float32 OpenEXR
    file, atomically (readers never see a partial file). ``channels`` names the channels
    [default: ``Y``; ``R, G, B``; ``R, G, B, A``]."""
    a = np.asarray(image, dtype=np.float32)
    if a.ndim == 2:
        a = a[:, :, None]
    if a.ndim != 3:
        raise ValueError(f"an image must be (H, W) or (H, W, C), got shape {a.shape}")
    h, w, c = a.shape
    if channels is None:
        defaults = {1: ["Y"], 3: ["R", "G", "B"], 4: ["R", "G", "B", "A"]}
        if c not in defaults:
            raise ValueError(f"name the {c} channels (channels=[...])")
        channels = defaults[c]
    if len(channels) != c:
        raise ValueError(f"{len(channels)} channel names for {c} channels")
    planes = [(str(n), np.ascontiguousarray(a[:, :, k]).reshape(-1)) for k, n in enumerate(channels)]
    _core.write_exr(str(path), w, h, planes)


def _rgb(name: str, a: Any) -> np.ndarray:
    """An image argument as float32 (H, W, 3): (H, W) is grey, a fourth channel is dropped."""
    a = np.asarray(a, dtype=np.float32)
    if a.ndim == 2:
        a = np.repeat(a[:, :, None], 3, axis=2)
    if a.ndim != 3 or a.shape[2] not in (3, 4):
        raise ValueError(f"{name} must be (H, W), (H, W, 3) or (H, W, 4), got shape {a.shape}")
    return np.ascontiguousarray(a[:, :, :3])


def compare(
    image: np.ndarray,
    reference: np.ndarray,
    image_variance: Optional[np.ndarray] = None,
    reference_variance: Optional[np.ndarray] = None,
    block: int = 16,
    alpha: float = 0.01,
    flip_exposure: float = 0.0,
) -> Dict[str, Any]:
    """The figures ``pt compare`` prints, as a dict.

    Keys: ``relmse``, ``rmse``, ``mae``, ``mean_ratio`` (per channel R, G, B), ``relmse_all``,
    ``nonfinite_pixels`` and ``fireflies`` (image, reference), ``flip`` (mean FLIP after tone
    mapping both at ``flip_exposure`` stops) and ``flip_map`` (H, W), ``ztest`` and ``agree``.

    With both variances (of each image's pixel means, as ``render(..., variance=True)`` and
    ``pt render --variance`` give them), ``ztest`` holds the block z-test (``block`` pixels
    square, family-wise level ``alpha``, Šidák-corrected, plus a chi-square of all blocks):
    ``pass``, ``max_abs_z``, ``failed`` of ``tests``, ``chi2``, ``chi2_p``, and the per-pixel
    test's ``pixel_fraction_failed``; else it is None. ``agree``: no non-finite pixel in the
    image and the block test passed (or was not run), ``pt compare``'s exit code 0.
    """
    img = _rgb("image", image)
    ref = _rgb("reference", reference)
    if img.shape != ref.shape:
        raise ValueError(f"image is {img.shape[1]}x{img.shape[0]} but the reference is {ref.shape[1]}x{ref.shape[0]}")
    h, w, _ = img.shape
    flat = lambda a: a.reshape(-1, 3)  # noqa: E731
    variances = None
    if (image_variance is None) != (reference_variance is None):
        raise ValueError("the z-test needs both variances (image_variance and reference_variance)")
    if image_variance is not None:
        iv, rv = _rgb("image_variance", image_variance), _rgb("reference_variance", reference_variance)
        if iv.shape != img.shape or rv.shape != img.shape:
            raise ValueError("the variances must have the images' size")
        variances = (flat(iv), flat(rv))
    return _core.compare(w, h, flat(img), flat(ref), variances, int(block), float(alpha), float(flip_exposure))


class Bsdf:
    """A BSDF model with its parameters (from :func:`bsdf`), evaluated over arrays.

    Directions are in the local shading frame (z along the normal), both pointing away from the
    surface: ``wo`` towards the viewer, ``wi`` towards the light; float arrays (N, 3), or one
    (3,) direction broadcast against the other argument's rows. In spectral mode every method
    takes ``wavelengths`` (nm): one per row, or one for all.
    """

    def __init__(self, core: "_core.BsdfCore") -> None:
        self._core = core

    @property
    def mode(self) -> str:
        """``"rgb"`` or ``"spectral"``."""
        return self._core.mode

    def __repr__(self) -> str:
        return repr(self._core)

    def eval(self, wo: Any, wi: Any, wavelengths: Any = None, cosine: bool = False) -> np.ndarray:
        """f(wo, wi), float32 (N, 3): r, g, b in RGB mode; in spectral mode the value at each
        row's wavelength, in all three columns. Without the cosine, as pt's BSDFs define it;
        ``cosine=True`` multiplies by |cos theta_i| (what Mitsuba's ``eval`` returns)."""
        a, c = _pair(wo, wi)
        f = self._core.eval(a, c, _wavelengths(wavelengths, a.shape[0]))
        return f * np.abs(c[:, 2:3]).astype(np.float32) if cosine else f

    def pdf(self, wo: Any, wi: Any, wavelengths: Any = None) -> np.ndarray:
        """The solid-angle density of sampling ``wi`` given ``wo``, float32 (N,)."""
        a, c = _pair(wo, wi)
        return self._core.pdf(a, c, _wavelengths(wavelengths, a.shape[0]))

    def sample(
        self,
        wo: Any,
        u: Optional[np.ndarray] = None,
        wavelengths: Any = None,
        n: Optional[int] = None,
        seed: int = 0,
    ) -> Dict[str, np.ndarray]:
        """Samples ``wi`` given ``wo`` from ``u`` (N, 3) uniform numbers in [0, 1) (lobe choice,
        then two for the direction), or from ``n`` rows of ``numpy.random.default_rng(seed)``.

        Returns ``wi`` (N, 3), ``weight`` = f |cos theta_i| / pdf (N, 3), ``pdf`` (N,) (for a
        delta lobe, its discrete probability), ``delta`` and ``valid`` (N,) booleans; rows
        where sampling failed are zeros with ``valid`` False."""
        w = _directions(wo, "wo")
        if u is None:
            rows = n if n is not None else w.shape[0]
            u = np.random.default_rng(seed).random((rows, 3))
        u = np.ascontiguousarray(np.asarray(u, dtype=np.float64))
        if u.ndim != 2 or u.shape[1] != 3:
            raise ValueError(f"u must be (N, 3), got shape {u.shape}")
        if w.shape[0] == 1 and u.shape[0] != 1:
            w = np.repeat(w, u.shape[0], axis=0)
        if w.shape[0] != u.shape[0]:
            raise ValueError(f"wo has {w.shape[0]} rows but u has {u.shape[0]}")
        wi, weight, p, delta, valid = self._core.sample(w, u, _wavelengths(wavelengths, w.shape[0]))
        return {"wi": wi, "weight": weight, "pdf": p, "delta": delta, "valid": valid}


def bsdf(model: str, two_sided: bool = False, mode: str = "rgb", **params: Any) -> Bsdf:
    """A BSDF built as a scene file's ``<bsdf type="model">`` with these parameters would be
    (Mitsuba's names and defaults; :func:`bsdf_models` lists them), for example
    ``bsdf("roughconductor", alpha=0.2, material="Au")``.

    Values: numbers, ``True``/``False``, RGB triples (linear sRGB) and names
    (``material="Au"``, ``int_ior="bk7"``, ``distribution="ggx"``). ``two_sided`` wraps it in
    ``twosided``. ``mode="spectral"`` builds it as a spectral render does (colours upsampled,
    named materials and indices at each wavelength); its methods then need ``wavelengths``.
    An unknown model or parameter, or a value out of range, raises :class:`SceneError`.
    """
    values = []
    for name, v in params.items():
        if isinstance(v, (bool, np.bool_)):
            v = bool(v)
        elif isinstance(v, (int, float, np.integer, np.floating)):
            v = float(v)
        elif isinstance(v, str):
            pass
        else:
            t = tuple(float(x) for x in v)
            if len(t) != 3:
                raise ValueError(f"{model} {name}: a colour has three values (r, g, b), got {len(t)}")
            v = t
        values.append((name, v))
    return Bsdf(_core.bsdf(model, values, bool(two_sided), mode))


def bsdf_models() -> Dict[str, List[str]]:
    """The models :func:`bsdf` builds, each with the parameters it accepts."""
    return {name: list(params) for name, params in _core.bsdf_models()}


def _directions(a: Any, name: str) -> np.ndarray:
    """Directions as float64 (N, 3); a single (3,) vector becomes one row."""
    d = np.asarray(a, dtype=np.float64)
    if d.ndim == 1:
        d = d[None, :]
    if d.ndim != 2 or d.shape[1] != 3:
        raise ValueError(f"{name} must be (N, 3) or (3,), got shape {d.shape}")
    return np.ascontiguousarray(d)


def _pair(wo: Any, wi: Any) -> Tuple[np.ndarray, np.ndarray]:
    """``wo`` and ``wi`` with the same number of rows (a single row is repeated)."""
    a, b = _directions(wo, "wo"), _directions(wi, "wi")
    if a.shape[0] != b.shape[0]:
        if a.shape[0] == 1:
            a = np.repeat(a, b.shape[0], axis=0)
        elif b.shape[0] == 1:
            b = np.repeat(b, a.shape[0], axis=0)
        else:
            raise ValueError(f"wo has {a.shape[0]} rows but wi has {b.shape[0]}")
    return a, b


def _wavelengths(lam: Any, n: int) -> Optional[np.ndarray]:
    """Wavelengths as float64 (N,); one value is used for every row."""
    if lam is None:
        return None
    out = np.asarray(lam, dtype=np.float64).reshape(-1)
    if out.size == 1 and n != 1:
        out = np.full(n, out[0])
    return np.ascontiguousarray(out)


def converge(
    scene: PathLike,
    reference: PathLike,
    spp: Sequence[int] = (1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024),
    strategies: Sequence[str] = ("mis",),
    integrators: Sequence[str] = ("path",),
    modes: Sequence[str] = (),
    out: Optional[PathLike] = None,
    threads: Optional[int] = None,
    max_depth: Optional[int] = None,
    seed: int = 1000,
    mitsuba: bool = False,
    log: Optional[Callable[[str], Any]] = None,
    **params: Any,
) -> Dict[str, Any]:
    """``pt converge``: error against render time, one curve per strategy, method and mode
    (and Mitsuba 3's, with ``mitsuba=True``, run by this interpreter, which must import
    ``mitsuba``). Writes ``converge.csv``, ``converge.svg``, ``converge.png`` and
    ``summary.txt`` to ``out`` [default: ``converge-<scene name>``].

    Returns ``{"table": rows, "summary": text}``: one row per point, a dict of ``curve``,
    ``spp``, ``seconds``, ``relmse``, ``rmse``, ``flip`` (the CSV's columns), and the summary
    ``pt converge`` prints (time ratios to reach each error level). ``log`` receives the
    progress lines. Keyword arguments are scene parameters (``-D``), passed to Mitsuba too.
    """
    import sys

    scene_path = _existing_file(scene)
    out_dir = Path(out) if out is not None else Path(f"converge-{scene_path.stem}")
    series, summary = _core.converge(
        str(scene_path),
        str(_existing_file(reference)),
        [int(s) for s in spp],
        list(strategies),
        list(integrators),
        list(modes),
        str(out_dir),
        threads,
        max_depth,
        int(seed),
        _defines(params),
        sys.executable if mitsuba else None,
        log,
    )
    table = [
        {"curve": name, "spp": s, "seconds": t, "relmse": e, "rmse": r, "flip": f}
        for name, points in series
        for (s, t, e, r, f) in points
    ]
    return {"table": table, "summary": summary}
