"""Figures: lens layout with rays, spot diagrams, ray fans, field curvature and distortion,
RMS map, MTF curves, design progress, wavefront map, OPD fans, Seidel diagram, encircled
energy.

Every function builds a ``matplotlib.figure.Figure`` with the Agg canvas (no pyplot, no
display needed) and returns it; ``save(fig, path)`` writes it. Conventions: lengths in mm
(spot coordinates in µm), field angles in degrees, wavelengths in µm, light toward +z
(left to right in layouts), the meridional plane is y–z.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence

import jax
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .io.json_values import output_file, whole_path

_WL_COLORS = {0.4861327: "tab:blue", 0.5875618: "tab:green", 0.6562725: "tab:red"}
_FIELD_COLORS = ("tab:blue", "tab:green", "tab:red", "tab:purple", "tab:orange", "tab:brown")
MAX_LAYOUT_RAYS = 1024
"""Most rays per fan that ``plot_layout`` draws: beyond a few hundred a fan is a filled area;
``n_rays=10**9`` asked for 8 GB of pupil coordinates before tracing a billion rays."""


def _figure(w: float, h: float) -> Figure:
    fig = Figure(figsize=(w, h), dpi=110)
    FigureCanvasAgg(fig)
    return fig


def save(fig: Figure, path: str | os.PathLike) -> str:
    """Write a figure (format from the extension) and return the path."""
    if not isinstance(path, str | os.PathLike):
        output_file(path, "save")  # refuses it, naming save (os.fspath's TypeError did not)
    path = os.fspath(path)
    if not isinstance(fig, Figure):
        raise TypeError(f"save: fig must be a matplotlib Figure, got {type(fig).__name__}")
    if not path.strip() or os.path.isdir(path):  # '' wrote nothing and returned ''
        raise ValueError(f"save: path must be a file name (its extension gives the format, "
                         f".png), got {path!r}")
    with whole_path(path, "save") as tmp:  # written whole or not at all (the extension kept)
        fig.savefig(tmp, bbox_inches="tight")
    return path


def _wl_color(w: float, i: int) -> str:
    for k, c in _WL_COLORS.items():
        if abs(k - w) < 1e-3:
            return c
    return _FIELD_COLORS[i % len(_FIELD_COLORS)]


def _default_fields(lens, fractions) -> list:
    """The fields a figure shows when none are given: ``fractions`` of the largest y field
    (repeats dropped), or the lens's own (θx, θy) fields, since a system that is not
    rotationally symmetric may image nothing useful at angles it was not set up for."""
    f = np.asarray(lens.fields, np.float64)
    if f.ndim == 2:
        return [tuple(map(float, v)) for v in f]
    fmax = float(np.max(np.abs(f)))
    return sorted({float(a) * fmax for a in fractions})


def _field_label(f, lens=None) -> str:
    """A field for a legend: degrees, or mm for an object-space telecentric lens's object
    heights."""
    u = " mm" if getattr(lens, "telecentric_object", False) else "°"
    f = np.asarray(f, float) + 0.0  # −0.0 + 0.0 is 0.0: no "-0.0" label
    return f"{f:.1f}{u}" if np.ndim(f) == 0 else f"({f[0]:.1f}{u}, {f[1]:.1f}{u})"


def _denoised(v, floor: float = 1e-9):
    """Plotted values with rounding noise (|v| below ``floor`` in their unit, e.g. % of
    distortion) and negative zeros set to 0.0, so that an axis of noise reads 0, not an
    offset of 1e-14 or "-0.000000"."""
    v = np.asarray(v, float)
    return np.where(np.abs(v) < floor, 0.0, v) + 0.0


def _profile(surface, r):
    import jax.numpy as jnp

    z, _ = surface.sag(jnp.zeros_like(r), r)
    return np.asarray(z)


@jax.jit
def _fans(lens, fields, pupil):
    """Each field's meridional fan, launched and after every surface: one compiled program,
    kept between figures (op by op the traces took seconds per field)."""
    from .imaging import sampling
    from .tracing.forward import trace_path

    depth = sampling.lens_depth(lens, None, "plot_layout")  # from the lens's own object

    def one(f):
        rays = sampling.field_rays(lens, f, pupil, depth=depth)
        return rays.origin, rays.direction, trace_path(lens, rays)

    return jax.vmap(one)(fields)


def plot_layout(lens, fields: Sequence[float] | None = None, *, n_rays: int = 9,
                semi_diameters=None, title: str | None = None) -> Figure:
    """Meridional section of the lens with ray fans.

    Args:
        lens: the lens.
        fields: field angles (deg) of the ray fans, θy or (θx, θy) pairs (the section is
            y–z: x fields are drawn projected); default 0, 70 % and 100 % of the
            lens's largest field.
        n_rays: rays per fan across the entrance pupil (primary wavelength).
        semi_diameters: surface semi-diameters to draw (default
            ``analysis.clear_semi_diameters``).
        title: figure title.
    """
    import jax.numpy as jnp

    from .analysis import spots as analysis
    from .optics import checks
    from .optics.coordinates import CoordinateBreak, frame_of

    lens = lens.astype(jnp.float64)
    fields = _default_fields(lens, (0.0, 0.7, 1.0)) if fields is None else list(fields)
    checks.field_angles(fields, "plot_layout", "fields")  # here, not deep in the program
    checks.number(n_rays, "n_rays", "plot_layout", lo=1, integer=True, unit="rays per fan")
    if n_rays > MAX_LAYOUT_RAYS:
        raise ValueError(f"plot_layout: n_rays must be at most {MAX_LAYOUT_RAYS} rays per fan "
                         f"(plot.MAX_LAYOUT_RAYS: beyond a few hundred a fan is a "
                         f"filled area), got {n_rays}")
    u = np.linspace(-1.0, 1.0, n_rays)
    pupil = jnp.asarray(np.stack([np.zeros_like(u), u], -1))
    fan_fields = jnp.asarray(fields, lens.epd.dtype)
    if semi_diameters is None and fan_fields.ndim == np.ndim(lens.fields):
        # One compiled program for both (with ray aiming, 13 s of compiling become 8).
        sd, starts, dirs, paths = analysis.semi_diameters_and_fans(lens, fan_fields, pupil)
    else:
        sd = analysis.clear_semi_diameters(lens) if semi_diameters is None else semi_diameters
        starts, dirs, paths = _fans(lens, fan_fields, pupil)
    # On the host once: indexing the device arrays below compiled a program per slice shape.
    sd, starts, dirs, paths = jax.tree.map(np.asarray, (sd, starts, dirs, paths))
    zs = np.asarray(lens.vertex_z())
    n = lens.num_surfaces
    # Each surface's tracer frame in global coordinates (identity without coordinate breaks):
    # drawn in the tracer's frames, a decentered or tilted system would come apart.
    frames = [tuple(np.asarray(a) for a in frame_of(lens, i)) for i in range(n)]
    frames.append(tuple(np.asarray(a) for a in frame_of(lens, None)))

    def zy(i, p):
        """Global (z, y) of tracer-frame points p [..., 3] of surface i (n: the image)."""
        rot, off = frames[i]
        g = np.asarray(p) @ rot.T + off
        return g[..., 2], g[..., 1]

    def section(i, y, z):
        """Global (z, y) of the points (0, y, z) of surface i's frame."""
        return zy(i, np.stack([np.zeros_like(y), y, z], -1))

    fig = _figure(8, 4.5)
    ax = fig.add_subplot(1, 1, 1)
    # Rays.
    for i, f in enumerate(fields):
        start, d0 = np.asarray(starts[i]), np.asarray(dirs[i])
        path = np.asarray(paths.origin[i])
        # Start the drawn rays a little in front of the first surface.
        t0 = (-0.5 - start[:, 2]) / d0[:, 2]
        pts = [zy(0, start + t0[:, None] * d0)] + [zy(k, path[k]) for k in range(n + 1)]
        valid = np.asarray(paths.valid[i, -1])
        zz = np.stack([p[0] for p in pts])
        ys = np.stack([p[1] for p in pts])
        color = _FIELD_COLORS[i % len(_FIELD_COLORS)]
        for j in range(n_rays):
            ax.plot(zz[:, j], ys[:, j], color=color, lw=0.6, alpha=0.9 if valid[j] else 0.25,
                    ls="-" if valid[j] else ":")
        ax.plot([], [], color=color, lw=1, label=_field_label(f, lens))
    # Surfaces and element edges (coordinate breaks are not drawn).
    n_air = [float(np.asarray(m.extrapolated_index(0.5875618))) for m in lens.materials]

    def edge_z(i):
        return zs[i] + float(_profile(lens.surfaces[i], jnp.asarray([sd[i]]))[0])

    prev = None
    for i, s in enumerate(lens.surfaces):
        if isinstance(s, CoordinateBreak):
            continue
        if i == lens.stop:
            r = sd[i]
            for sign in (1, -1):
                ax.plot(*section(i, sign * np.array([r, 1.25 * r]), np.full(2, zs[i])),
                        color="k", lw=2)
            prev = None
            continue
        r = np.linspace(-sd[i], sd[i], 101)
        ax.plot(*section(i, r, zs[i] + _profile(s, jnp.asarray(r))), color="k", lw=1)
        glass_after = abs(n_air[i] - 1.0) > 1e-6
        if prev is not None:
            j = prev
            rr = max(sd[i], sd[j])
            for sign in (1, -1):
                ax.plot(*section(j, sign * np.array([sd[j], rr]), np.full(2, edge_z(j))),
                        color="k", lw=1)
                ax.plot(*section(i, sign * np.array([sd[i], rr]), np.full(2, edge_z(i))),
                        color="k", lw=1)
                # The rim between the two surfaces' edges (one frame: no break inside glass).
                ax.plot(*section(i, np.full(2, sign * rr), np.array([edge_z(j), edge_z(i)])),
                        color="k", lw=1)
        prev = i if glass_after else None
    h = float(np.max(sd)) * 1.1
    if lens.sensor is not None:
        h = max(h, float(np.asarray(lens.sensor.half_diagonal)))
    on_image = np.asarray(paths.origin[:, -1, :, 1])[np.asarray(paths.valid[:, -1])]
    if on_image.size:  # long enough for every drawn ray to end on it
        h = max(h, 1.05 * float(np.max(np.abs(on_image))))
    r = np.linspace(-h, h, 101)  # the image surface as it is (curved, tilted)
    ax.plot(*section(n, r, float(lens.image_z()) + _profile(lens.image, jnp.asarray(r))),
            color="k", lw=2)
    ax.set_aspect("equal")
    ax.set_xlabel("z (mm)")
    ax.set_ylabel("y (mm)")
    ax.legend(loc="upper left", fontsize=8, title="field", title_fontsize=8)
    ax.set_title(title or (lens.name or "lens"))
    return fig


def plot_spots(lens, fields: Sequence[float] | None = None, *, wavelengths=None,
               rings: int = 12, title: str | None = None) -> Figure:
    """Spot diagrams (µm about the polychromatic centroid) for fields θy or (θx, θy) in
    degrees; default five y fields from 0 to the largest, or the lens's own (θx, θy) fields."""
    import jax.numpy as jnp

    from .analysis import spots as analysis
    from .imaging import sampling
    from .optics import checks

    checks.focal_image(lens, "plot_spots")
    lens = lens.astype(jnp.float64)
    fields = _default_fields(lens, np.linspace(0, 1, 5)) if fields is None else list(fields)
    wls = np.asarray(lens.wavelengths if wavelengths is None else wavelengths)
    pupil = sampling.pupil_hexapolar(rings, jnp.float64)
    fig = _figure(2.6 * len(fields), 2.9)
    spots = []
    for f in fields:
        pts = []
        for w in wls:
            r = analysis.spot_rays(lens, f, float(w), pupil=pupil)
            p = np.asarray(r.origin[:, :2])[np.asarray(r.valid)]
            pts.append(p)
        allp = np.concatenate(pts) if any(len(p) for p in pts) else np.zeros((1, 2))
        c = allp.mean(0)
        rms = math.sqrt(np.mean(np.sum((allp - c) ** 2, -1))) * 1e3
        spots.append((pts, c, rms))
    lim = max(max(np.max(np.abs(np.concatenate(p) - c)) if len(np.concatenate(p)) else 0
                  for p, c, _ in spots) * 1e3, 1.0) * 1.05
    for k, (f, (pts, c, rms)) in enumerate(zip(fields, spots, strict=True)):
        ax = fig.add_subplot(1, len(fields), k + 1)
        for i, (w, p) in enumerate(zip(wls, pts, strict=True)):
            if len(p):
                ax.scatter((p[:, 0] - c[0]) * 1e3, (p[:, 1] - c[1]) * 1e3, s=1.5,
                           color=_wl_color(float(w), i), label=f"{w:.3f} µm")
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        ax.set_aspect("equal")
        ax.set_title(f"{_field_label(f, lens)}  RMS {rms:.2f} µm", fontsize=8)
        ax.tick_params(labelsize=7)
        if k == 0:
            ax.set_ylabel("µm")
    fig.suptitle(title or "spot diagrams (about the polychromatic centroid)", fontsize=9)
    return fig


def plot_rms_map(rms_um, sensor_size, *, title: str | None = None) -> Figure:
    """RMS spot radius over the sensor from an n × n field grid (µm).

    Args:
        rms_um: ``[n, n]`` (rows along y from −h/2 to h/2) or ``[n²]`` values.
        sensor_size: (height, width) in mm.
        title: figure title.
    """
    from .optics import checks

    checks.real_values(rms_um, "rms_um", "plot_rms_map", "µm")  # "5" was read as 5
    v = np.asarray(rms_um, float)
    n = int(round(math.sqrt(v.size)))
    if v.size == 0 or n * n != v.size or v.ndim not in (1, 2):
        raise ValueError(f"plot_rms_map: rms_um must be [n, n] or [n²] values (µm), got shape "
                         f"{v.shape}")
    v = v.reshape(n, n)
    # A negative or swapped size would draw a mirrored map with wrong axis labels.
    if not isinstance(sensor_size, tuple | list) or len(sensor_size) != 2:
        raise ValueError(f"plot_rms_map: sensor_size must be (height, width) in mm, got "
                         f"{sensor_size!r}")
    h, w = (checks.number(x, "sensor_size", "plot_rms_map", lo=0, lo_open=True, unit="mm")
            for x in sensor_size)
    fig = _figure(5, 4.2)
    ax = fig.add_subplot(1, 1, 1)
    im = ax.imshow(v, origin="lower", extent=(-w / 2, w / 2, -h / 2, h / 2), cmap="viridis",
                   interpolation="nearest")
    fig.colorbar(im, ax=ax, label="RMS spot radius (µm)")
    ax.set_xlabel("x on sensor (mm)")
    ax.set_ylabel("y on sensor (mm)")
    ok = np.isfinite(v)
    if not ok.any():  # before: a blank map titled "mean nan µm, max nan µm"
        raise ValueError(f"plot_rms_map: rms_um has no finite value (all {v.size} fields "
                         f"without an RMS: every ray lost?), got {checks.fmt(v.ravel()[:1])}")
    lost = f"; {int((~ok).sum())} fields without an RMS (blank)" if not ok.all() else ""
    ax.set_title(title or f"RMS over {v.size} fields: mean {v[ok].mean():.2f} µm, "
                 f"max {v[ok].max():.2f} µm{lost}", fontsize=9)
    return fig


def plot_mtf(lens, fields: Sequence[float] | None = None, *, frequencies=None,
             title: str | None = None) -> Figure:
    """Tangential (solid) and sagittal (dashed) polychromatic MTF (``jaxlens.imaging.psf.mtf``,
    geometric × diffraction limit) for fields θy or (θx, θy) in degrees; default 0, 50, 70 and
    100 % of the largest y field, or the lens's own (θx, θy) fields."""
    import jax.numpy as jnp

    from .imaging.psf import NoLightError, mtf

    lens = lens.astype(jnp.float64)
    fields = _default_fields(lens, (0.0, 0.5, 0.7, 1.0)) if fields is None else list(fields)
    fig = _figure(6, 4.2)
    ax = fig.add_subplot(1, 1, 1)
    for i, f in enumerate(fields):
        c = _FIELD_COLORS[i % len(_FIELD_COLORS)]
        try:
            res = mtf(lens, f, frequencies=frequencies)
        except NoLightError:  # a field without light has no MTF (it was drawn as 0)
            ax.plot([], [], color=c, ls=":", label=f"{_field_label(f, lens)}: no light")
            continue
        freq, tan, sag = (np.asarray(x) for x in _mtf_parts(res))
        ax.plot(freq, tan, color=c, label=f"{_field_label(f, lens)} T")
        ax.plot(freq, sag, color=c, ls="--", label=f"{_field_label(f, lens)} S")
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("spatial frequency (cycles/mm)")
    ax.set_ylabel("MTF")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    ax.set_title(title or "MTF (geometric × diffraction limit)", fontsize=9)
    return fig


def _mtf_parts(res):
    """(frequencies, tangential, sagittal) from ``psf.mtf``'s result."""
    if isinstance(res, tuple):
        return res[0], res[1], res[2]
    return res.frequencies, res.tangential, res.sagittal


def plot_ray_fans(lens, fields: Sequence[float] | None = None, *, wavelengths=None,
                  n: int = 41, title: str | None = None) -> Figure:
    """Transverse ray fans (``jaxlens.analysis.aberrations.ray_fan``, µm against the primary
    chief ray): a row per field θy or (θx, θy) in degrees, tangential e_y against Py on the
    left, sagittal e_x against Px on the right; default 0, 70 and 100 % of the largest y
    field, or the lens's own (θx, θy) fields. Lost rays leave gaps."""
    import jax.numpy as jnp

    from .analysis.aberrations import ray_fan

    lens = lens.astype(jnp.float64)
    fields = _default_fields(lens, (0.0, 0.7, 1.0)) if fields is None else list(fields)
    fans = [ray_fan(lens, f, wavelengths, n=n) for f in fields]
    lim = max([float(np.nanmax(np.abs(np.concatenate([np.asarray(r.tangential).ravel(),
                                                       np.asarray(r.sagittal).ravel()]))))
               for r in fans if bool(np.any(r.valid_tangential) or np.any(r.valid_sagittal))]
              + [1e-6]) * 1e3 * 1.05
    return _fan_grid(fields, fans, lim, 1e3, ("e_y (µm)", "e_x (µm)"),
                     title or "ray fans (transverse error against the primary chief ray)", lens)


def _fan_grid(fields, fans, lim, scale, ylabels, title, lens=None) -> Figure:
    """A row per field, the tangential fan against Py on the left and the sagittal against
    Px on the right, a line per wavelength (``fans[k].tangential``/``.sagittal`` ``[W, n]``
    times ``scale``, on ``fans[k].pupil``); shared by the ray and OPD fan figures."""
    fig = _figure(6.4, 1.9 * len(fields) + 0.6)
    fig.set_layout_engine("constrained")
    for k, (f, r) in enumerate(zip(fields, fans, strict=True)):
        t = np.asarray(r.pupil)
        for j, (vals, name) in enumerate(((r.tangential, "tangential"),
                                          (r.sagittal, "sagittal"))):
            ax = fig.add_subplot(len(fields), 2, 2 * k + j + 1)
            for i, w in enumerate(np.asarray(r.wavelengths)):
                ax.plot(t, np.asarray(vals[i]) * scale, color=_wl_color(float(w), i), lw=1,
                        label=f"{w:.3f} µm")
            ax.axhline(0, color="k", lw=0.4)
            ax.set_ylim(-lim, lim)
            ax.tick_params(labelsize=7)
            ax.set_title(f"{_field_label(f, lens)} {name}", fontsize=8)
            ax.set_ylabel(ylabels[j], fontsize=7)
            if k == len(fields) - 1:
                ax.set_xlabel("Py" if j == 0 else "Px", fontsize=7)
    fig.axes[0].legend(fontsize=6)
    fig.suptitle(title, fontsize=9)
    return fig


def plot_field_curvature(lens, *, wavelengths=None, title: str | None = None) -> Figure:
    """Field curvature (tangential foci dashed, sagittal solid, mm from the image surface,
    per wavelength) and distortion (% against f·tanθ, primary wavelength) over θy from 0 to
    the largest field (``jaxlens.analysis.aberrations.field_curvature``, ``spots.distortion``);
    for an object-space telecentric lens over the object height y (mm), distortion against
    m·h."""
    import jax.numpy as jnp

    from .analysis.aberrations import default_fields
    from .analysis.report_cells import bucketed_field_curvature
    from .analysis.spots import distortion

    lens = lens.astype(jnp.float64)
    fields = default_fields(lens, 21)
    fc = bucketed_field_curvature(lens, fields, wavelengths)  # the report's program
    dist = distortion(lens, fields)
    th = np.asarray(fields)
    fig = _figure(7, 4)
    fig.set_layout_engine("constrained")
    ax = fig.add_subplot(1, 2, 1)
    for i, w in enumerate(np.asarray(fc.wavelengths)):
        c = _wl_color(float(w), i)
        ax.plot(np.asarray(fc.tangential[i]), th, color=c, ls="--", lw=1, label=f"{w:.3f} T")
        ax.plot(np.asarray(fc.sagittal[i]), th, color=c, lw=1, label=f"{w:.3f} S")
    ax.axvline(0, color="k", lw=0.4)
    ax.set_xlabel("focus from the image surface (mm)")
    tele = lens.telecentric_object  # object heights (mm), distortion against m·h
    ax.set_ylabel("object height y (mm)" if tele else "field θy (deg)")
    ax.set_ylim(0, max(float(th[-1]), 1e-9))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6)
    ax.set_title("field curvature", fontsize=8)
    ax = fig.add_subplot(1, 2, 2)
    # Distortion is 0/0 on axis: drawn from the first field off it. Rounding noise (an
    # ideal lens's 1e-14 %) is drawn as the 0 it is: its axis read "1e-14" and "-0.000000".
    ax.plot(_denoised(dist.percent_ftan)[1:], th[1:], color="k", lw=1,
            label="against m·h" if tele else "against f·tanθ")
    ax.plot(_denoised(dist.percent_paraxial)[1:], th[1:], color="k", lw=1, ls="--",
            label="against the paraxial chief ray (parallel to the axis at h)" if tele else
            "against the paraxial chief ray (OpticStudio's F-Tan)")
    ax.axvline(0, color="k", lw=0.4)
    ax.legend(fontsize=6)
    ax.set_xlabel("distortion (%)")
    ax.set_ylim(0, max(float(th[-1]), 1e-9))
    ax.grid(alpha=0.3)
    ax.set_title("distortion", fontsize=8)
    fig.suptitle(title or "field curvature and distortion", fontsize=9)
    return fig


def plot_progress(history, *, title: str | None = None) -> Figure:
    """Spot RMS (µm, log scale) of every design over the steps, stages marked."""
    if not (hasattr(history, "stages") and hasattr(history, "spot_rms")):
        raise TypeError(f"plot_progress: history must be a design History (DesignResult."
                        f"history), got {type(history).__name__}")
    fig = _figure(7, 4)
    ax = fig.add_subplot(1, 1, 1)
    offset = 0
    for name, r in zip(history.stages, history.spot_rms, strict=True):
        r = np.asarray(r)
        if r.size == 0:
            continue
        steps = offset + np.arange(r.shape[0])
        r = r.reshape(r.shape[0], -1)
        for j in range(r.shape[1]):
            ax.plot(steps, r[:, j] * 1e3, lw=0.8, color=f"C{j % 10}")
        ax.axvline(offset, color="k", lw=0.5, alpha=0.4)
        ax.text(offset, 1.0, name, rotation=90, fontsize=6, va="top",
                transform=ax.get_xaxis_transform())
        offset += r.shape[0]
    ax.set_yscale("log")
    ax.set_xlabel("step")
    ax.set_ylabel("loss-field spot RMS (µm)")
    ax.grid(alpha=0.3, which="both")
    ax.set_title(title or "design progress (one line per seed)", fontsize=9)
    return fig


def plot_image(img, *, title: str | None = None) -> Figure:
    """Show an ``[H, W, 3]`` (or ``[H, W]`` grey) float image in [0, 1] (values beyond are
    clipped). An integer image (sRGB codes), NaN or ±inf, or another shape is refused
    (``ValueError``): before, a uint8 image was clipped to white and black, and NaN drew
    nothing."""
    from .optics import checks

    a = checks.float_image(img, "plot_image", hint=" (a rendered or decoded image)")
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[-1] != 3) or a.size == 0:
        raise ValueError(f"plot_image: img must be an [H, W, 3] or [H, W] image of at least "
                         f"one pixel, got shape {a.shape}")
    fig = _figure(5, 5)
    ax = fig.add_subplot(1, 1, 1)
    ax.imshow(np.clip(a, 0, 1), cmap="gray" if a.ndim == 2 else None)
    ax.set_axis_off()
    if title:
        ax.set_title(title, fontsize=9)
    return fig


def plot_tolerance_histogram(mc: dict, *, title: str | None = None) -> Figure:
    """Monte-Carlo RMS distribution (``jaxlens.analysis.tolerance.monte_carlo``'s result):
    RMS after refocusing (filled) and without the compensator (outline), µm."""
    if not (isinstance(mc, dict) and "per_trial" in mc and "nominal" in mc):
        raise ValueError("plot_tolerance_histogram: mc must be the dict that "
                         "jaxlens.analysis.tolerance.monte_carlo returns (keys 'per_trial', "
                         f"'nominal'), got {type(mc).__name__}"
                         f"{f' with keys {sorted(mc)}' if isinstance(mc, dict) else ''}")
    per = mc["per_trial"]
    rc = np.asarray(per["rms_compensated_um"], float)
    r0 = np.asarray(per["rms_um"], float)
    fin = np.concatenate([rc[np.isfinite(rc)], r0[np.isfinite(r0)]])
    bins = np.linspace(fin.min(), fin.max(), 31) if fin.size else 10
    fig = _figure(6, 4.0)
    ax = fig.add_subplot(1, 1, 1)
    ax.hist(rc[np.isfinite(rc)], bins=bins, color="tab:blue", alpha=0.7,
            label="back focus refocused")
    ax.hist(r0[np.isfinite(r0)], bins=bins, histtype="step", color="tab:gray",
            label="no compensator")
    for x, style, lab in ((mc["nominal"]["rms_um"], "k-", "nominal"),
                          (mc["rms_p50_um"], "b--", "p50"), (mc["rms_p90_um"], "b:", "p90"),
                          (mc["threshold_um"], "r-", "threshold")):
        ax.axvline(x, color=style[0], ls=style[1:], lw=1.2, label=f"{lab} {x:.2f} µm")
    ax.set_xlabel("mean RMS spot radius over the fields (µm)")
    ax.set_ylabel("trials")
    ax.legend(fontsize=7)
    ax.set_title(title or f"Monte-Carlo tolerancing: {mc['trials']} trials, yield "
                 f"{100 * mc['yield']:.0f} % at {mc['threshold_um']:g} µm", fontsize=9)
    return fig


# --------------------------------------------------------------------------------------
# Wavefront error, OPD fans, Seidel diagram, encircled energy
# --------------------------------------------------------------------------------------

_SEIDEL_NAMES = ("spherical", "coma", "astigmatism", "Petzval", "distortion", "axial colour",
                 "lateral colour")


def _largest_field(lens):
    """The lens's largest field: θy (sign kept), or the (θx, θy) pair of largest radial angle."""
    f = np.asarray(lens.fields, np.float64)
    if f.ndim == 2:
        t = np.tan(np.deg2rad(f))
        return tuple(map(float, f[int(np.argmax(np.sum(t * t, -1)))]))
    f = f.reshape(-1)
    return float(f[int(np.argmax(np.abs(f)))])


def _checked_fields(lens, fields, fractions, where: str) -> list:
    """The fields given (or the default ones), checked before any tracing."""
    from .imaging import telecentric

    fields = _default_fields(lens, fractions) if fields is None else list(fields)
    if not fields:
        raise ValueError(f"{where}: fields must hold at least one field (θy or (θx, θy) in "
                         f"degrees), got none")
    telecentric.lens_fields(lens, fields, where)  # heights (mm) or angles (deg), untraced
    return fields


def _one_field(field, where: str, lens=None):
    """One field θy or (θx, θy) in degrees (an object height y or (x, y) in mm for an
    object-space telecentric ``lens``), checked before any tracing, as Python floats."""
    from .imaging import telecentric
    from .optics import checks

    if getattr(lens, "telecentric_object", False):
        field = np.asarray(telecentric.one_height(field, where))
    else:
        field = np.asarray(checks.one_field(field, where))
    return float(field) if field.ndim == 0 else tuple(map(float, field))


def plot_wavefront(lens, field=None, *, wavelength=None, grid: int = 65,
                   title: str | None = None) -> Figure:
    """The wavefront map (OPD to the exit-pupil reference sphere, waves; positive where the
    wavefront is ahead of the sphere) of one field over the normalised entrance pupil (Px,
    Py), from ``jaxlens.analysis.wavefront``: a diverging colour scale centred on 0, blank
    outside the disc and where rays are vignetted. The title gives the RMS and P-V (piston
    removed, tilt kept) and Maréchal's Strehl ratio (tilt removed), the latter only where
    the RMS with tilt removed is at most ``MARECHAL_MAX_RMS`` wave.

    Args:
        lens: the lens.
        field: θy or (θx, θy) in degrees (an object height in mm, y or (x, y), for an
            object-space telecentric lens); default the lens's largest field.
        wavelength: µm; default the primary wavelength.
        grid: pupil samples per side (odd keeps the chief ray on the grid).
        title: first line of the title (the statistics follow below it).
    """
    import jax.numpy as jnp

    from .analysis.wavefront_error import MARECHAL_MAX_RMS, wavefront

    lens = lens.astype(jnp.float64)
    field = _largest_field(lens) if field is None else _one_field(field, "plot_wavefront", lens)
    # Fields go to the analyses as arrays: a (θx, θy) tuple makes jnp.shape warn there.
    wf = wavefront(lens, np.asarray(field), wavelength=wavelength, grid=grid)
    m, valid, p = np.asarray(wf.map), np.asarray(wf.valid), np.asarray(wf.pupil)
    wl = float(wf.wavelength)
    lim = max(float(np.max(np.abs(m[valid]))) if valid.any() else 0.0, 1e-6)
    h = (p[1] - p[0]) / 2
    fig = _figure(5.2, 4.6)
    ax = fig.add_subplot(1, 1, 1)
    im = ax.imshow(m, origin="lower", extent=(p[0] - h, p[-1] + h, p[0] - h, p[-1] + h),
                   cmap="RdBu_r", vmin=-lim, vmax=lim, interpolation="nearest")
    fig.colorbar(im, ax=ax, label=f"OPD (waves at {wl:.4f} µm)")
    ax.set_aspect("equal")
    ax.set_xlabel("Px (normalised entrance pupil)")
    ax.set_ylabel("Py")
    # A field no ray reaches was drawn as an empty map; wavefront refuses it (NoLightError).
    sigma = float(wf.rms_tilt_removed)
    stats = f"RMS {float(wf.rms):.4f} waves, P-V {float(wf.pv):.4f} waves\n"
    stats += (f"Strehl {float(wf.strehl):.3f} (Maréchal)" if sigma <= MARECHAL_MAX_RMS
              else f"no Strehl: RMS tilt removed {sigma:.3f} > {MARECHAL_MAX_RMS:g} wave "
                   f"(Maréchal)")
    ax.set_title(f"{title or f'wavefront map, {_field_label(field, lens)}'}\n{stats}", fontsize=8)
    return fig


def plot_opd_fans(lens, fields: Sequence[float] | None = None, *, wavelengths=None,
                  n: int = 41, title: str | None = None) -> Figure:
    """OPD fans (``jaxlens.analysis.opd_fan``, waves at each wavelength against its own chief
    ray and reference sphere): a row per field θy or (θx, θy) in degrees, tangential (OPD
    against Py) on the left, sagittal (against Px) on the right; default 0, 70 and 100 % of
    the largest y field, or the lens's own (θx, θy) fields. Vignetted rays leave gaps."""
    import jax.numpy as jnp

    from .analysis.wavefront_error import opd_fan

    lens = lens.astype(jnp.float64)
    fields = _checked_fields(lens, fields, (0.0, 0.7, 1.0), "plot_opd_fans")
    fans = [opd_fan(lens, np.asarray(f), wavelengths, n=n) for f in fields]
    vals = np.concatenate([np.asarray(x).ravel() for r in fans
                           for x in (r.tangential, r.sagittal)])
    vals = vals[np.isfinite(vals)]
    lim = max(float(np.max(np.abs(vals))) if vals.size else 0.0, 1e-6) * 1.05
    return _fan_grid(fields, fans, lim, 1.0, ("OPD (waves)", "OPD (waves)"),
                     title or "OPD fans (waves at each wavelength, against its chief ray)", lens)


def plot_seidel(lens, *, title: str | None = None) -> Figure:
    """Seidel diagram (``jaxlens.analysis.seidel`` at the largest field and the primary
    wavelength): for each surface (numbered as in ``lens.surfaces``, from 0) and for the
    sum, a bar per wavefront term W040 (spherical), W131 (coma), W222 (astigmatism), W220P
    (Petzval), W311 (distortion), W020 (axial colour), W111 (lateral colour), in waves of the
    primary wavelength, with Welford's sign (``analysis.third_order``). A lens that
    third-order theory does not cover raises ``seidel``'s ValueError before anything is
    drawn."""
    import jax.numpy as jnp

    from .analysis.third_order import WAVEFRONT_TERMS, seidel

    s = seidel(lens.astype(jnp.float64))
    w = np.asarray(s.wavefront(per_surface=True))  # [7, n] waves
    data = np.concatenate([w, np.asarray(s.wavefront())[:, None]], 1)  # sum last
    n = w.shape[1]
    labels = [f"{i}\nstop" if i == lens.stop else str(i) for i in range(n)] + ["Sum"]
    fig = _figure(max(6.0, 0.75 * (n + 1) + 2.0), 4.2)
    ax = fig.add_subplot(1, 1, 1)
    x = np.arange(n + 1, dtype=float)
    width = 0.8 / len(WAVEFRONT_TERMS)
    for k, (term, name) in enumerate(zip(WAVEFRONT_TERMS, _SEIDEL_NAMES, strict=True)):
        ax.bar(x + (k - (len(WAVEFRONT_TERMS) - 1) / 2) * width, data[k], width,
               color=f"C{k}", label=f"{term} {name}")
    ax.axhline(0, color="k", lw=0.5)
    ax.axvline(n - 0.5, color="k", lw=0.5, ls=":")
    ax.set_xticks(x, labels, fontsize=7)
    ax.set_xlabel("surface")
    ax.set_ylabel(f"waves at {float(s.wavelength):.4f} µm")
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=6, ncol=2)
    where = (f"object height {float(s.field):.2f} mm" if lens.telecentric_object
             else f"field {float(s.field):.1f}°")
    ax.set_title(title or f"Seidel diagram, {where} "
                 f"({lens.name or 'lens'})", fontsize=9)
    return fig


def plot_encircled_energy(lens, fields: Sequence[float] | None = None, *,
                          method: str = "geometric", max_radius=None, wavelength=None,
                          pixel_size=None, title: str | None = None) -> Figure:
    """Encircled energy against the radius from the energy centroid (µm), one line per field
    θy or (θx, θy) in degrees (``jaxlens.analysis.encircled_energy``), each field's D80
    radius marked (``radius_for_fraction(…, 0.8)``; the legend gives the diameter D80).

    Args:
        lens: the lens.
        fields: default 0, 70 and 100 % of the largest y field, or the lens's own (θx, θy)
            fields.
        method: ``"geometric"`` or ``"diffraction"`` (which needs ``pixel_size``).
        max_radius: the largest radius drawn, in µm as the x axis (> 0); default 1.5 times
            the largest of the fields' radii holding 99 % of the energy.
        wavelength: µm, one or ``[W]`` (pooled); default the primary wavelength.
        pixel_size: diffraction: the PSF pitch in mm.
        title: figure title.
    """
    import jax.numpy as jnp

    from .analysis.encircled import energy_samples, energy_within, radius_holding
    from .optics import checks

    where = "plot_encircled_energy"
    lens = lens.astype(jnp.float64)
    fields = _checked_fields(lens, fields, (0.0, 0.7, 1.0), where)
    if max_radius is not None:
        max_radius = checks.number(max_radius, "max_radius", where, lo=0, lo_open=True,
                                   unit="µm")
    # Each field traced once: its curve and its 80 and 99 % radii from the same samples
    # (before: radius_for_fraction, then encircled_energy, traced each field twice).
    samples = [energy_samples(lens, np.asarray(f), method=method, wavelength=wavelength,
                              pixel_size=pixel_size, where=where) for f in fields]
    r80, r99 = np.asarray([radius_holding(s, jnp.asarray([0.8, 0.99])) for s in samples]).T
    if max_radius is None:
        top = r99[np.isfinite(r99)] if np.isfinite(r99).any() else 3 * r80[np.isfinite(r80)]
        max_radius = 1.5e3 * float(np.max(top)) if top.size else 1.0
    radii = np.linspace(0.0, max_radius, 201) * 1e-3  # mm
    fig = _figure(6, 4.2)
    ax = fig.add_subplot(1, 1, 1)
    for i, (f, r, s) in enumerate(zip(fields, r80, samples, strict=True)):
        c = _FIELD_COLORS[i % len(_FIELD_COLORS)]
        ee = np.asarray(energy_within(s, jnp.asarray(radii)).energy)
        d80 = f"D80 {2e3 * r:.2f} µm" if np.isfinite(r) else "no light"
        ax.plot(radii * 1e3, ee, color=c, lw=1, label=f"{_field_label(f, lens)}: {d80}")
        ax.plot([r * 1e3, r * 1e3], [0.0, 0.8], color=c, ls=":", lw=1)
    ax.axhline(0.8, color="k", lw=0.4)
    ax.set_xlim(0, max_radius)
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("radius from the energy centroid (µm)")
    ax.set_ylabel("encircled energy (fraction)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title(title or f"{method} encircled energy (dotted: the 80 % radius; legend: "
                          f"D80, its diameter)", fontsize=9)
    return fig
