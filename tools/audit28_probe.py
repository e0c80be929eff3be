# ruff: noqa: E501, B023, E731
"""Round-28 bad-input probes: the table of ``tools/audit22_probe.py`` (probe | outcome | what
happened) for round 27's two leftovers and for the public names and parameters that the
probe and test files still name least.

The count (``count_mentions`` of tools/audit27_probe.py, ``AUDIT27_COUNT=1``, rerun on main
at 4cda67e with round 27's two files counted too): after the result containers
(``RayFan``, ``Wavefront``, ``Evaluation``, ``StageArgs``…, named 0-1 times) come
``AbstractMaterial``/``ZernikeFit`` (3), ``OddAsphere``/``Plane``/``evaluate_design`` (8),
``XYPolynomial``/``trace_path`` (9), ``LensParams``/``random_params``/``opd``/``Conic``/
``Stop``/``Hybrid``/``trace_backward`` (10), ``Binary2``/``ZernikeSag``/``opd_fan`` (11) and
``LBFGSB`` (14; ``lower``/``upper`` 1 each), ``RayLoss`` (22; ``fracs`` and
``pupil_weights`` 0), ``Schott`` (20), ``radius_for_fraction`` (``fraction`` 0),
``CatalogMaterial`` (``catalog_vd`` 0). Most were already guarded (the controls below); the
gaps were the shapes of ``LensParams`` given to ``Parameterization.to_lens``, a solver's
``free`` flags, ``LBFGSB``'s bounds, a formula material's 2-D coefficients, and ``RayLoss``
and ``StageArgs`` built directly.

Round 27's leftovers:
1. ``Binary2(order=1.5)`` and ``order=0`` stay accepted. The order M multiplies the whole
   phase (Φ = M Σ A_i ρ^{2i}) and Zemax takes any real M for Binary 2 (a non-whole M scales
   the phase, as a harmonic or multi-order diffractive is modelled); ``Grating`` refuses a
   non-whole order because its M counts the lines' diffracted orders (M λ/Λ). Order 0 is
   documented as "the phase off" (the order-0 system of a design), so no warning either.
2. ``LensParams`` takes anything (it is a plain container, built by the design loop and by
   users for ``Parameterization.to_lens`` and the solvers). The solvers already refused a
   string (``lrs.c '1'``); ``to_lens`` gave an ``AttributeError`` ('str' object has no
   attribute 'dtype') — vague, not silent. The silent answers were the shapes: ``c`` of 2
   for 12 surfaces (JAX clamps the index: surfaces 3-12 took the second curvature), one
   aspheric term for six (broadcast over all six orders, each scaled by its own r_s power),
   a gap too many or too few (the lens's thickness list changed length), and an integer
   ``c`` (``r_norm`` cast to int: 1.17 mm read as 1, curvature 1.0/mm for 0.856/mm). All
   refused now, at trace time (shapes and dtypes are static, so under jit/vmap too).

Before (main at 4cda67e, an archive) and after (branch audit28), the same probes,
``PYTHONPATH=<tree> python tools/audit28_probe.py``, 47 probes, about 10 s each way:
    before: clear error: 11, crash: 2, ok: 11, silent wrong: 23
    after:  clear error: 36, ok: 11
The two "crash" rows on main are AttributeErrors that named nothing. The solver and
``RayLoss``/``StageArgs`` rows mark "silent wrong" an input accepted when built: LBFGSB then
moved a group flagged ``'no'`` and clipped every step to ``upper`` (swapped bounds);
damped least squares failed inside its first jitted step instead (equinox's "filter_spec
must consist of booleans and callables only").

Probe (before -> after):
    Binary2 order 1.5 (control: Zemax takes any real M; power ×1.5)    ok           -> ok
    Binary2 order 0 with phase (control: the phase off, as documented) ok           -> ok
    Grating order 1.5 (control: lines diffract whole orders)           clear error  -> clear error
    to_lens c '1' (a string)                                           crash        -> clear error
    to_lens c 0.1 (one number for 12 surfaces)                         crash        -> clear error
    to_lens c of 2 for 12 surfaces (index clamped)                     silent wrong -> clear error
    to_lens a 1 term for 6 (broadcast)                                 silent wrong -> clear error
    to_lens d 13 gaps for 12                                           silent wrong -> clear error
    to_lens d 11 gaps for 12                                           silent wrong -> clear error
    to_lens c integers (r_norm cast to int)                            silent wrong -> clear error
    to_lens from_lens round trip (control)                             ok           -> ok
    to_lens under jit and vmap (control)                               ok           -> ok
    Adam lrs.c '1' (control)                                           clear error  -> clear error
    LBFGSB free c 'no' (truthy: the group moves)                       silent wrong -> clear error
    DampedLeastSquares free c 'no'                                     silent wrong -> clear error
    Adam free c 0.5 (a half learning rate)                             silent wrong -> clear error
    Adam free k False (control)                                        ok           -> ok
    LBFGSB lower/upper swapped (clipped to upper)                      silent wrong -> clear error
    LBFGSB one gap's bounds crossed (d[1] 1.0 > 0.2)                   silent wrong -> clear error
    LBFGSB lower = upper (control: a pinned group)                     ok           -> ok
    LBFGSB ±inf (control)                                              ok           -> ok
    Schott coeffs [[6]] (six 'indices', two NaN)                       silent wrong -> clear error
    Conrady coeffs [[3]]                                               silent wrong -> clear error
    Schott coeffs 6 (control)                                          ok           -> ok
    Sellmeier 2-D B, C (control)                                       clear error  -> clear error
    RayLoss fracs 1.5 (past the corner)                                silent wrong -> clear error
    RayLoss fracs in percent (0, 100)                                  silent wrong -> clear error
    RayLoss 2 pupil_weights for 3 points                               silent wrong -> clear error
    RayLoss 3 areas for 2 fields                                       silent wrong -> clear error
    RayLoss wavelengths in nm                                          silent wrong -> clear error
    RayLoss pupil point (0.9, 0.9) outside the disc                    silent wrong -> clear error
    RayLoss pupil_weights negative                                     silent wrong -> clear error
    RayLoss.make (control)                                             ok           -> ok
    StageArgs beta 2 (blend past the centroid)                         silent wrong -> clear error
    StageArgs 2 reg_weights for 3                                      silent wrong -> clear error
    StageArgs epd NaN                                                  silent wrong -> clear error
    StageArgs field_weights negative                                   silent wrong -> clear error
    StageArgs batched (control: the design loop's [B])                 ok           -> ok
    StageArgs traced beta 2 under jit (not checked)                    ok           -> ok
    XYPolynomial norm_radius 0                                         clear error  -> clear error
    ZernikeSag decenter_y NaN                                          clear error  -> clear error
    Biconic kx NaN                                                     clear error  -> clear error
    CatalogMaterial catalog nd/vd swapped                              clear error  -> clear error
    CatalogMaterial wavelength_range in nm                             clear error  -> clear error
    radius_for_fraction 80 (percent)                                   clear error  -> clear error
    opd_fan n 10**8                                                    clear error  -> clear error
    random_params dtype int32                                          clear error  -> clear error

Run: PYTHONPATH=$PWD python tools/audit28_probe.py [filter]
"""

import os
import sys

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probe_table import probe, run  # noqa: E402

import jaxlens as jl  # noqa: E402
import jaxlens.analysis as A  # noqa: E402
import jaxlens.design as D  # noqa: E402
from jaxlens import zoo  # noqa: E402
from jaxlens.optics.materials import Conrady  # noqa: E402

P = D.LensParams


# ----------------------------------------------------------------------------- round 27's leftovers
def leftovers():
    base = jl.Binary2(phase_coeffs=[-100.0], norm_radius=5.0)
    p1 = float(base.paraxial_power(0.55))
    p15 = float(jl.Binary2(order=1.5, phase_coeffs=[-100.0], norm_radius=5.0).paraxial_power(0.55))
    probe("Binary2 order 1.5 (control: Zemax takes any real M; power ×1.5)", lambda: p15 / p1, good=abs(p15 / p1 - 1.5) < 1e-12)
    probe("Binary2 order 0 with phase (control: the phase off, as documented)", lambda: float(jl.Binary2(order=0.0, phase_coeffs=[-100.0]).paraxial_power(0.55)), good=True)
    probe("Grating order 1.5 (control: lines diffract whole orders)", lambda: jl.Grating(lines_per_um=0.1, order=1.5), "order", "whole")

    spec = D.DesignSpec()
    pm = D.parameterization(spec)
    p = D.random_params(spec, jax.random.PRNGKey(0))
    s, g = p.c.shape[0], p.d.shape[0]
    lens = lambda **k: pm.to_lens(P(**{"c": p.c, "a": p.a, "k": p.k, "d": p.d, **k}))
    probe("to_lens c '1' (a string)", lambda: lens(c="1"), "params.c", "float array")
    probe("to_lens c 0.1 (one number for 12 surfaces)", lambda: lens(c=0.1), "params.c", f"({s},)")
    probe(f"to_lens c of 2 for {s} surfaces (index clamped)", lambda: [float(x.c) for x in lens(c=p.c[:2]).surfaces[1:4]], "params.c", f"({s},)")
    probe("to_lens a 1 term for 6 (broadcast)", lambda: lens(a=p.a[:, :1]).surfaces[1].coeffs, "params.a", "aspheric")
    probe(f"to_lens d {g + 1} gaps for {g}", lambda: lens(d=jnp.concatenate([p.d, p.d[:1]])).thickness.shape, "params.d", f"({g},)")
    probe(f"to_lens d {g - 1} gaps for {g}", lambda: lens(d=p.d[:-1]).thickness.shape, "params.d", f"({g},)")
    probe("to_lens c integers (r_norm cast to int)", lambda: (float(lens(c=jnp.ones(s, int)).surfaces[1].c), 1 / float(pm.r_norm[0])), "params.c", "int")
    probe("to_lens from_lens round trip (control)", lambda: float(jnp.max(jnp.abs(pm.from_lens(lens()).c - p.c))), good=True)
    probe("to_lens under jit and vmap (control)", lambda: jax.vmap(jax.jit(lambda c: pm.to_lens(P(c, p.a, p.k, p.d)).surfaces[1].c))(jnp.stack([p.c, p.c])), good=True)
    probe("Adam lrs.c '1' (control)", lambda: D.Adam(lambda q, a: q, lrs=P(c="1", a=1e-3, k=1e-3, d=1e-3)), "lrs.c")


# ----------------------------------------------------------------------------- least-named names
def least_named():
    lrs = P(c=1e-3, a=1e-3, k=1e-3, d=1e-3)
    one, inf = P(c=1.0, a=1.0, k=1.0, d=1.0), P(c=np.inf, a=np.inf, k=np.inf, d=np.inf)
    probe("LBFGSB free c 'no' (truthy: the group moves)", lambda: D.LBFGSB(lambda q, a: q, lower=one, upper=inf, free=P(c="no", a=True, k=False, d=True)), "free.c", "True or False")
    probe("DampedLeastSquares free c 'no'", lambda: D.DampedLeastSquares(lambda q, a: q, free=P(c="no", a=True, k=False, d=True)), "free.c")
    probe("Adam free c 0.5 (a half learning rate)", lambda: D.Adam(lambda q, a: q, lrs=lrs, free=P(c=0.5, a=True, k=False, d=True)), "free.c")
    probe("Adam free k False (control)", lambda: D.Adam(lambda q, a: q, lrs=lrs, free=P(c=True, a=True, k=False, d=True)), good=True)
    lo, hi = P(c=-1.0, a=-1.0, k=-1.0, d=jnp.array([0.5, 1.0])), P(c=1.0, a=1.0, k=1.0, d=jnp.array([5.0, 0.2]))
    probe("LBFGSB lower/upper swapped (clipped to upper)", lambda: D.LBFGSB(lambda q, a: q, lower=hi, upper=lo), "lower.c", "upper.c", "swapped")
    probe("LBFGSB one gap's bounds crossed (d[1] 1.0 > 0.2)", lambda: D.LBFGSB(lambda q, a: q, lower=lo, upper=hi), "lower.d", "(1,)")
    probe("LBFGSB lower = upper (control: a pinned group)", lambda: D.LBFGSB(lambda q, a: q, lower=one, upper=one), good=True)
    probe("LBFGSB ±inf (control)", lambda: D.LBFGSB(lambda q, a: q, lower=P(c=-np.inf, a=-np.inf, k=-np.inf, d=0.1), upper=inf), good=True)

    schott = [2.27, -0.0101, 0.0108, 2e-4, -8e-6, 1e-6]
    probe("Schott coeffs [[6]] (six 'indices', two NaN)", lambda: jl.Schott([schott]).index(0.55), "coeffs", "1-D array")
    probe("Conrady coeffs [[3]]", lambda: Conrady([[1.5, 0.01, 1e-4]]).index(0.55), "coeffs", "1-D")
    probe("Schott coeffs 6 (control)", lambda: float(jl.Schott(schott).index(0.55)), good=True)
    probe("Sellmeier 2-D B, C (control)", lambda: jl.Sellmeier([[1.0, 0.2]], [[0.006, 0.02]]), "B and C", "1-D")

    def ray_loss(**k):
        a = dict(fracs=jnp.array([0.0, 1.0]), area=jnp.ones(2), pupil=jnp.zeros((3, 2)),
                 pupil_weights=jnp.ones(3), wavelengths=jnp.array([0.55]))
        a.update(k)
        return lambda: D.RayLoss(**a)
    probe("RayLoss fracs 1.5 (past the corner)", ray_loss(fracs=jnp.array([0.0, 1.5])), "fracs", "[0, 1]")
    probe("RayLoss fracs in percent (0, 100)", ray_loss(fracs=jnp.array([0.0, 100.0])), "fracs")
    probe("RayLoss 2 pupil_weights for 3 points", ray_loss(pupil_weights=jnp.ones(2)), "pupil_weights", "(3,)")
    probe("RayLoss 3 areas for 2 fields", ray_loss(area=jnp.ones(3)), "area", "(2,)")
    probe("RayLoss wavelengths in nm", ray_loss(wavelengths=jnp.array([550.0])), "wavelengths", "nm")
    probe("RayLoss pupil point (0.9, 0.9) outside the disc", ray_loss(pupil=jnp.array([[0.0, 0.0], [0.9, 0.9], [0.0, 0.5]])), "pupil", "unit disc")
    probe("RayLoss pupil_weights negative", ray_loss(pupil_weights=jnp.array([1.0, -1.0, 1.0])), "pupil_weights")
    probe("RayLoss.make (control)", lambda: D.RayLoss.make(5, 6, [0.486, 0.5876, 0.656], (24.0, 36.0)).pupil.shape, good=True)

    def stage(**k):
        a = dict(tan_max=0.3, epd=10.0, focal=50.0, beta=0.0, pin=0.0, spot_scale=1.0,
                 field_weights=jnp.ones(3), reg_weights=jnp.ones(3))
        a.update(k)
        return lambda: D.StageArgs(**a)
    probe("StageArgs beta 2 (blend past the centroid)", stage(beta=2.0), "beta", "[0, 1]")
    probe("StageArgs 2 reg_weights for 3", stage(reg_weights=jnp.ones(2)), "reg_weights", "3")
    probe("StageArgs epd NaN", stage(epd=np.nan), "epd", "mm")
    probe("StageArgs field_weights negative", stage(field_weights=jnp.array([1.0, -1.0, 1.0])), "field_weights")
    probe("StageArgs batched (control: the design loop's [B])", stage(tan_max=jnp.full(4, 0.3), field_weights=jnp.ones((4, 3)), reg_weights=jnp.ones((4, 3))), good=True)
    probe("StageArgs traced beta 2 under jit (not checked)", lambda: float(jax.jit(lambda b: stage(beta=b)().beta)(2.0)), good=True)

    # Controls: least-named names already guarded.
    probe("XYPolynomial norm_radius 0", lambda: jl.XYPolynomial(coeffs=[0, 0, 1e-3], norm_radius=0.0), "norm_radius")
    probe("ZernikeSag decenter_y NaN", lambda: jl.ZernikeSag(zernike=[0, 1e-3], decenter_y=np.nan), "decenter_y")
    probe("Biconic kx NaN", lambda: jl.Biconic(c=0.01, cx=0.02, kx=np.nan), "kx")
    probe("CatalogMaterial catalog nd/vd swapped", lambda: jl.CatalogMaterial(jl.get_material("N-BK7"), "X", catalog_nd=64.17, catalog_vd=1.5168), "catalog_nd")
    probe("CatalogMaterial wavelength_range in nm", lambda: jl.CatalogMaterial(jl.get_material("N-BK7"), "X", wavelength_range=(300.0, 2500.0)), "wavelength_range", "nm")
    lens = zoo.cooke_triplet()
    probe("radius_for_fraction 80 (percent)", lambda: A.radius_for_fraction(lens, 0.0, 80.0), "fraction")
    probe("opd_fan n 10**8", lambda: A.opd_fan(lens, 0.0, n=10**8), "n")
    probe("random_params dtype int32", lambda: D.random_params(D.DesignSpec(), jax.random.PRNGKey(0), dtype=jnp.int32), "dtype")


run([leftovers, least_named])
