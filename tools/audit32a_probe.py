# ruff: noqa: E501, B023, E731
"""Round-32a bad-input probes: the table of ``tools/audit22_probe.py`` (probe | outcome | what
happened) for the Python API (jaxlens, optics, tracing, imaging, analysis, design, zoo, nets)
past what rounds 26-31 reached. Round 32b probes the command lines and the file formats.

The count (``probe_table.mention_counts``, rerun on main at f920cd8 with round 31 counted;
``AUDIT32A_COUNT=1`` here prints it; ``jaxlens.zoo`` and ``jaxlens.nets``, which
``PACKAGES`` leaves out, counted by hand): after the result containers (``EncircledEnergy``,
``Seidel``, ``SolverResult``…, 0-4) the least named were the networks and the zoo —
``double_gauss`` (1), ``Depthwise``/``Pointwise`` (4; ``c_in``/``c_out`` 0),
``num_parameters`` (6), ``LayerNorm2d``/``simple_gate`` (7), ``cellphone6`` (8), ``Conv``
(12; ``kernel`` 1), ``Upsample`` (13), ``NAFBlock`` (32; ``ffn_expand`` 1), ``NAFNet`` (37;
``identity_init`` 0) — then the parameters named 0-2 times: ``radius_for_fraction``'s
``fraction`` (0), ``zernike_nm``'s ``j`` (0), ``Seidel.wavefront``'s ``per_surface`` (0),
``DampedLeastSquares``'s ``lam0``, ``catalog_names``'
``obsolete``/``catalog`` (2), ``reversed_lens``' ``image_distance``, ``trace_path``'s
``uniform``, ``Hybrid``'s ``odd_x``/``odd_y``, ``Biconic``'s ``kx``, ``paper_stages``'
``final_loss`` (1), ``CatalogMaterial``'s ``catalog_vd`` (1), ``DesignConfig``'s
``lr_d``/``lr_k``/``lr_m``/``population``/``polish_rings`` (1-2), ``Aperture``'s
``half_x``/``blocks``, and the lenses the brief names: mirrors, coordinate breaks, a stop on
the last surface, an object 1 µm away, a zero-thickness glass; and slips under ``jax.jit``.

Gaps found and fixed:
1. ``nets``: ``Conv``/``Pointwise``/``Depthwise``/``LayerNorm2d(dtype=jnp.int32)`` made
   integer weights (a Conv's all 0; NAFBlock and NAFNet refused it already): refused.
2. ``nets``: a ``Depthwise`` or ``LayerNorm2d`` built for 3 channels broadcast a 1-channel
   image to 3 channels without a word; ``Conv`` and ``Depthwise`` given ``[H, W]`` failed
   inside lax / on unpacking: each layer checks its input's channels (static shapes, so
   under jit too).
3. ``nets``: the layers cast their weights to the input's dtype, so an integer image
   (0 … 191) ran with integer weights: NAFNet's answer differed from the float image's by
   108, a Conv's by 178, a trained NAFBlock's by 0.32. An integer input is computed in the
   weights' float dtype (max difference 0 now).
4. ``nets``: ``Conv(kernel=4)`` with stride 1 ('SAME' padding of an even kernel: the image
   shifted half a pixel) refused; ``NAFNet(identity_init="no")`` (truthy) and ``0`` are not
   booleans; ``enc_blocks=2`` was "object of type 'int' has no len()".
5. ``spot_rays``/``rms_spot``/``clear_semi_diameters``/``angular_spot``: a pupil point at
   radius 1.5 traced a ray 0.75 EPD off axis into the spot (a larger spot, or a vignetted
   ray counted in ``valid_fraction``), where ``opd`` and ``encircled_energy`` refused it.
   Refused now (``spots.unit_pupil``; under jit an ``eqx.error_if``), with a slack of a few
   ulps of the points' dtype: ``pupil_hexapolar``'s float32 rim lies at 1 + 2.3e-8.
6. ``Seidel.wavefront(per_surface="no")`` gave the ``[7, n]`` per-surface table where the
   ``[7]`` sums were meant; ``0`` gave the sums. Must be True or False (and ``transverse``).
7. ``paper_stages(final_loss="imag")`` was refused as the fine-tune Stage's ``loss``.
8. ``self_intersection`` measured each gap as Δz whichever way the light went, so every
   mirror lens read as crossed: a concave mirror with its focus 100 mm before it had gap
   -100 mm and ok False, a Cassegrain's -60.4 mm. The gap is negated where light travels
   toward −z (``travel.travel_senses``, static: a lens without mirrors compiles as before);
   an image plane that cuts the mirror's rim is still caught.
9. ``wavefront``/``opd``/``opd_fan`` took 20° typed as 0.349 (radians) without a word,
   where ``rms_spot``, ``chief_ray`` and ``ray_fan`` warn: they warn now.
10. ``catalog_names(catalogs=[])`` listed no glass, silently (and ``get_material(...,
    catalogs=())`` said the glass "is in catalog SCHOTT, not searched here"): refused.

Controls of note: ``sine_path(n=0)`` (one stage, documented), ``random_starts`` with a seed
twice (``design`` pads a device batch with repeats), ``reversed_lens(image_distance=-5)``,
``trace_path(upto=0)`` (0-based), ``DesignConfig(polish_rings=0)`` (the stages' rings), a
stop on the last surface, an object 1 µm away, a zero-thickness glass, integer fields, a
traced NaN EPD under jit (NaN spots: traced lenses are not re-checked, as documented).

Not fixed (files outside this round, with the fix):
- ``trace_path(uniform="no")`` traces as True (jaxlens/tracing/forward.py, the lead's):
  ``checks.switch(uniform, "uniform", "trace_path")``.
- ``psf``/``mtf`` of a field 0.349 (20° in radians) do not warn (jaxlens/imaging/psf.py is
  at 800 lines; its field goes through ``checks.field_angles``): warning in
  ``checks.one_field``/``field_angles`` for concrete values would cover psf, mtf and the
  wavefront analyses at once (then drop the two lines added to ``wavefront_error._common``).
- ``opd(lens, f, pupil_hexapolar(8, jnp.float32))`` is refused ("radius 1"): the rim points
  lie at 1 + 2.3e-8 in float32, past ``sampling.UNIT_DISC_TOLERANCE`` = 1e-9 (sampling.py,
  the lead's): a slack of a few ulps of the points' dtype, as ``spots.unit_pupil`` uses.

Before (main at f920cd8, an archive) and after (branch audit32a), the same probes,
``PYTHONPATH=<tree> python tools/audit32a_probe.py`` from the repository, 225 probes,
about 75 s each way:
    before: clear error: 167, ok: 29, silent wrong: 25, vague error: 4
    after:  clear error: 189, ok: 34, silent wrong: 2

A row marked "(warns)" or naming radians counts a warning as the answer ("clear error" when
it names the slip). A row "against floats" or "(true: …)" compares with the right answer:
"silent wrong" where it differs.

Probe (before -> after):
    double_gauss clip 'no'                                                                                     clear error  -> clear error
    cellphone6 clip 0                                                                                          clear error  -> clear error
    double_gauss clip False (control)                                                                          ok           -> ok
    Conv c_in 0                                                                                                clear error  -> clear error
    Conv kernel 2.5                                                                                            clear error  -> clear error
    Conv stride 2 with kernel 3                                                                                clear error  -> clear error
    Conv key 0 (an int)                                                                                        clear error  -> clear error
    Conv dtype int32                                                                                           silent wrong -> clear error
    Conv called on 2 channels (built for 3)                                                                    clear error  -> clear error
    Conv called on [8, 8] (no channel axis)                                                                    vague error  -> clear error
    Conv kernel 4 stride 1 (even 'SAME')                                                                       silent wrong -> clear error
    Conv 3x3 (control)                                                                                         ok           -> ok
    Pointwise c_out 10**9                                                                                      clear error  -> clear error
    Pointwise c_in -4                                                                                          clear error  -> clear error
    Pointwise dtype int32                                                                                      silent wrong -> clear error
    Pointwise called on 2 channels (built for 3)                                                               clear error  -> clear error
    Depthwise channels 0                                                                                       clear error  -> clear error
    Depthwise called on 1 channel (built for 3)                                                                silent wrong -> clear error
    Depthwise called on [8, 8]                                                                                 vague error  -> clear error
    LayerNorm2d eps 0                                                                                          clear error  -> clear error
    LayerNorm2d eps NaN                                                                                        clear error  -> clear error
    LayerNorm2d called on 1 channel (built for 3)                                                              silent wrong -> clear error
    LayerNorm2d dtype int32                                                                                    silent wrong -> clear error
    simple_gate 3 channels                                                                                     clear error  -> clear error
    simple_gate a scalar                                                                                       clear error  -> clear error
    NAFBlock channels 0                                                                                        clear error  -> clear error
    NAFBlock ffn_expand 0                                                                                      clear error  -> clear error
    NAFBlock dw_expand 2.5                                                                                     clear error  -> clear error
    NAFBlock dw_expand 10**6                                                                                   clear error  -> clear error
    NAFBlock called on 3 channels (built for 4)                                                                clear error  -> clear error
    NAFBlock dtype int32                                                                                       clear error  -> clear error
    Upsample c_in 3 (odd)                                                                                      clear error  -> clear error
    Upsample called on 2 channels (built for 4)                                                                clear error  -> clear error
    NAFNet identity_init 'no'                                                                                  silent wrong -> clear error
    NAFNet identity_init 0                                                                                     silent wrong -> clear error
    NAFNet in_channels 0                                                                                       clear error  -> clear error
    NAFNet in_channels 1, out_channels 3                                                                       clear error  -> clear error
    NAFNet enc_blocks (1, 1), dec_blocks (1, 1, 1)                                                             clear error  -> clear error
    NAFNet enc_blocks () dec_blocks () (control: no levels)                                                    ok           -> ok
    NAFNet enc_blocks 2 (an int)                                                                               vague error  -> clear error
    NAFNet width 2.5                                                                                           clear error  -> clear error
    NAFNet dtype int32                                                                                         clear error  -> clear error
    NAFNet image [8, 8] (no channel axis)                                                                      clear error  -> clear error
    NAFNet image [2, 8, 8, 3] (a batch)                                                                        clear error  -> clear error
    NAFNet image int 0..191 (against the same image as floats)                                                 silent wrong -> ok
    Conv called on an int image (against floats)                                                               silent wrong -> ok
    NAFBlock (trained scales) called on an int image (against floats)                                          silent wrong -> ok
    NAFNet image bool                                                                                          clear error  -> clear error
    NAFNet image complex                                                                                       clear error  -> clear error
    NAFNet image NaN                                                                                           clear error  -> clear error
    NAFNet image NaN under jit                                                                                 clear error  -> clear error
    NAFNet image 1x1 (control: padded by repeating it)                                                         ok           -> ok
    NAFNet image 8x8 (control)                                                                                 ok           -> ok
    num_parameters None                                                                                        clear error  -> clear error
    num_parameters a NAFNet (control)                                                                          ok           -> ok
    radius_for_fraction fraction 80 (percent)                                                                  clear error  -> clear error
    radius_for_fraction fraction 1.0                                                                           clear error  -> clear error
    radius_for_fraction fraction 80 under jit                                                                  clear error  -> clear error
    radius_for_fraction fraction [0.5, 0.8] (control)                                                          ok           -> ok
    zernike_nm j 0 (Noll starts at 1)                                                                          clear error  -> clear error
    zernike_nm j -1                                                                                            clear error  -> clear error
    zernike_nm j 2.5                                                                                           clear error  -> clear error
    zernike_nm j True                                                                                          clear error  -> clear error
    zernike_nm j 10**12                                                                                        clear error  -> clear error
    zernike_nm j 0 indexing 'ansi' (control: piston)                                                           ok           -> ok
    zernike_nm indexing 'nol'                                                                                  clear error  -> clear error
    Seidel.wavefront per_surface 'no'                                                                          silent wrong -> clear error
    Seidel.wavefront per_surface 0                                                                             silent wrong -> clear error
    Wavefront.zernike terms 0                                                                                  clear error  -> clear error
    Wavefront.zernike terms 10**6                                                                              clear error  -> clear error
    Wavefront.zernike terms 2.5                                                                                clear error  -> clear error
    Wavefront.zernike indexing 'nol'                                                                           clear error  -> clear error
    Wavefront.zernike terms 11 (control)                                                                       ok           -> ok
    angular_magnification wavelength 587.6 (nm)                                                                clear error  -> clear error
    angular_magnification wavelength NaN                                                                       clear error  -> clear error
    chief_ray field 100 (deg)                                                                                  clear error  -> clear error
    chief_ray field NaN                                                                                        clear error  -> clear error
    chief_ray field [0, 5, 10] (several)                                                                       clear error  -> clear error
    chief_ray field NaN under jit                                                                              clear error  -> clear error
    chief_ray field 100 under jit                                                                              clear error  -> clear error
    chief_ray depth 0                                                                                          clear error  -> clear error
    chief_ray aim 'reel'                                                                                       clear error  -> clear error
    spot_rays pupil [5, 3] (3 coordinates)                                                                     clear error  -> clear error
    spot_rays pupil [] (no points)                                                                             clear error  -> clear error
    spot_rays pupil (1.5, 0) (outside the unit pupil)                                                          silent wrong -> clear error
    spot_rays pupil complex                                                                                    clear error  -> clear error
    spot_rays pupil NaN under jit                                                                              clear error  -> clear error
    opd pupil shape (3,)                                                                                       clear error  -> clear error
    opd pupil (2, 0) (outside the unit pupil)                                                                  clear error  -> clear error
    opd pupil NaN                                                                                              clear error  -> clear error
    opd reference 'spherical'                                                                                  clear error  -> clear error
    opd pupil (0.3, 0.4) (control)                                                                             ok           -> ok
    opd_fan n 0                                                                                                clear error  -> clear error
    opd_fan n 10**8                                                                                            clear error  -> clear error
    opd_fan n 1                                                                                                clear error  -> clear error
    opd_fan wavelengths () (empty)                                                                             clear error  -> clear error
    ray_fan n 2.5                                                                                              clear error  -> clear error
    ray_fan wavelengths [] (empty)                                                                             clear error  -> clear error
    ray_fan field (0, 5, 10)                                                                                   clear error  -> clear error
    ray_fan wavelengths [486.1, 587.6] (nm)                                                                    clear error  -> clear error
    field_curvature fields () (empty)                                                                          clear error  -> clear error
    distortion fields [] (empty)                                                                               clear error  -> clear error
    rms_spot fields () (empty)                                                                                 clear error  -> clear error
    rms_spot wavelengths () (empty)                                                                            clear error  -> clear error
    angular_spot fields () (empty)                                                                             clear error  -> clear error
    clear_semi_diameters fields () (empty)                                                                     clear error  -> clear error
    clear_semi_diameters n_rim 0                                                                               clear error  -> clear error
    clear_semi_diameters reaching 'yes'                                                                        clear error  -> clear error
    rms_spot pupil (1.5, 0) (outside the unit pupil)                                                           silent wrong -> clear error
    spot_rays pupil (1.5, 0) under jit                                                                         silent wrong -> clear error
    spot_rays pupil hexapolar (control)                                                                        ok           -> ok
    trace_path uniform 'no'                                                                                    silent wrong -> silent wrong
    trace_path upto 0 (control: surface 1, 0-based)                                                            ok           -> ok
    trace_path upto 99                                                                                         clear error  -> clear error
    trace_backward upto 99                                                                                     clear error  -> clear error
    reversed_lens image_distance NaN                                                                           clear error  -> clear error
    reversed_lens image_distance -5 (control: an image before the last surface)                                ok           -> ok
    reversed_lens image_distance '10'                                                                          clear error  -> clear error
    reversed_lens (control)                                                                                    ok           -> ok
    Hybrid odd_x NaN                                                                                           clear error  -> clear error
    Hybrid odd_y 2-D                                                                                           clear error  -> clear error
    Biconic kx NaN                                                                                             clear error  -> clear error
    Biconic cx inf                                                                                             clear error  -> clear error
    Aperture shape 'rectangle'                                                                                 clear error  -> clear error
    Aperture half_x -1                                                                                         clear error  -> clear error
    Aperture half_y 0                                                                                          clear error  -> clear error
    Aperture blocks 'no'                                                                                       clear error  -> clear error
    Aperture decenter_x NaN                                                                                    clear error  -> clear error
    TiltedPlane tan_x 45 (degrees)                                                                             clear error  -> clear error
    Stop semi_diameter -1                                                                                      clear error  -> clear error
    Plane semi_diameter NaN                                                                                    clear error  -> clear error
    QTypeAsphere qtype 'bfs2'                                                                                  clear error  -> clear error
    QTypeAsphere norm_radius 0                                                                                 clear error  -> clear error
    Binary2 norm_radius 0                                                                                      clear error  -> clear error
    Binary2 order NaN                                                                                          clear error  -> clear error
    ZernikeSag norm_radius -1                                                                                  clear error  -> clear error
    ZernikeSag ordering 'fringe2'                                                                              clear error  -> clear error
    ZernikeSag extrapolate 'no'                                                                                clear error  -> clear error
    CoordinateBreak order 2                                                                                    clear error  -> clear error
    CoordinateBreak tilt_x NaN                                                                                 clear error  -> clear error
    Lens stop on the last surface (control)                                                                    ok           -> ok
    Lens stop 2 of 2 surfaces                                                                                  clear error  -> clear error
    Lens object_distance 1e-3 (control: a finite object 1 µm away)                                             ok           -> ok
    Lens object_distance 0                                                                                     clear error  -> clear error
    Lens object_distance -10                                                                                   clear error  -> clear error
    Lens thickness [0, 33.4] (zero-thickness glass; control)                                                   ok           -> ok
    Lens mirrors (5,) (out of range)                                                                           clear error  -> clear error
    Lens mirrors (0, 0) (twice)                                                                                clear error  -> clear error
    Lens obscurations {0: 20} (larger than the EPD)                                                            clear error  -> clear error
    Lens fields [0, 10] rad-looking (0.1745)                                                                   clear error  -> clear error
    Lens epd NaN in a traced lens (control: NaN spots, not re-checked under jit as documented)                 ok           -> ok
    Lens fields as ints [0, 10] (control)                                                                      ok           -> ok
    Lens wavelengths [0.5876] as a tuple (control)                                                             ok           -> ok
    Lens wavelengths () (empty)                                                                                clear error  -> clear error
    Lens fields () (empty)                                                                                     clear error  -> clear error
    Lens fields [[0, 5, 1]] (3 per field)                                                                      clear error  -> clear error
    Lens fields complex                                                                                        clear error  -> clear error
    Lens primary 1.0 (float)                                                                                   clear error  -> clear error
    Lens primary True                                                                                          clear error  -> clear error
    self_intersection a concave mirror, image 100 mm before it (true: no crossing)                             silent wrong -> ok
    self_intersection a mirror whose image plane cuts its rim (true: crossing; control)                        ok           -> ok
    self_intersection a Cassegrain, secondary 60 mm before the primary (true: no crossing)                     silent wrong -> ok
    efl of a concave mirror R -200 (control: 100)                                                              ok           -> ok
    rms_spot of a paraboloid on axis (control: 0)                                                              ok           -> ok
    render a mirror lens                                                                                       clear error  -> clear error
    seidel of a lens with a 5° coordinate break                                                                clear error  -> clear error
    rms_spot of a lens with a 5° coordinate break (control)                                                    ok           -> ok
    rms_spot fields and wavelengths swapped                                                                    clear error  -> clear error
    psf pixel_size 5 (µm)                                                                                      clear error  -> clear error
    psf field 0.349 (20° in radians)                                                                           silent wrong -> silent wrong
    wavefront field and wavelength swapped (0.5876, 14; wavelength is keyword-only)                            clear error  -> clear error
    wavefront field 0.349 (20° in radians)                                                                     silent wrong -> clear error
    opd field 0.349 (20° in radians)                                                                           silent wrong -> clear error
    opd_fan field 0.349 (20° in radians)                                                                       silent wrong -> clear error
    wavefront field 0.1745 (10° in radians)                                                                    silent wrong -> clear error
    wavefront field 14 (control)                                                                               ok           -> ok
    encircled_energy method 'geometric' with pupil_side 1 (a diffraction setting; refused whatever the method) clear error  -> clear error
    paper_stages final_loss 'imag'                                                                             vague error  -> clear error
    paper_stages n -1                                                                                          clear error  -> clear error
    paper_stages polish 'LM' (polish_steps 10)                                                                 clear error  -> clear error
    paper_stages solver 'Adam'                                                                                 clear error  -> clear error
    paper_stages polish 'lm' polish_steps 10 (control)                                                         ok           -> ok
    paper_stages pin -1                                                                                        clear error  -> clear error
    sensor_field_grid n 0                                                                                      clear error  -> clear error
    sensor_field_grid n 10**6                                                                                  clear error  -> clear error
    sine_path n 0 (control: one stage at the end, documented)                                                  ok           -> ok
    sine_path start NaN                                                                                        clear error  -> clear error
    sine_path n 10**10                                                                                         clear error  -> clear error
    random_params key 0 (an int)                                                                               clear error  -> clear error
    random_params dtype int32                                                                                  clear error  -> clear error
    random_starts seeds [] (none)                                                                              clear error  -> clear error
    random_starts seeds [1, 1] (control: design pads a device batch with repeats)                              ok           -> ok
    random_starts seeds -1                                                                                     clear error  -> clear error
    random_starts seeds 10**6 (a count?)                                                                       clear error  -> clear error
    evaluate_design min_valid 99 (percent)                                                                     clear error  -> clear error
    evaluate_design min_valid NaN                                                                              clear error  -> clear error
    evaluate_design n 0                                                                                        clear error  -> clear error
    DampedLeastSquares lam0 0                                                                                  clear error  -> clear error
    DampedLeastSquares lam0 NaN                                                                                clear error  -> clear error
    DampedLeastSquares inner 0                                                                                 clear error  -> clear error
    DampedLeastSquares residual_fn None                                                                        clear error  -> clear error
    LevenbergMarquardt rtol -1                                                                                 clear error  -> clear error
    LevenbergMarquardt atol NaN                                                                                clear error  -> clear error
    LevenbergMarquardt free 'all'                                                                              clear error  -> clear error
    catalog_names obsolete 'no'                                                                                clear error  -> clear error
    catalog_names catalog 'schot'                                                                              clear error  -> clear error
    catalog_names catalogs [] (none)                                                                           silent wrong -> clear error
    catalog_names catalog and catalogs both                                                                    clear error  -> clear error
    CatalogMaterial catalog_vd NaN                                                                             clear error  -> clear error
    CatalogMaterial catalog_nd 60, catalog_vd 1.5 (swapped)                                                    clear error  -> clear error
    CatalogMaterial formula 99                                                                                 clear error  -> clear error
    CatalogMaterial name 5                                                                                     clear error  -> clear error
    CatalogMaterial model None                                                                                 clear error  -> clear error
    CatalogMaterial wavelength_range (365, 2325) (nm)                                                          clear error  -> clear error
    TableMaterials wavelengths in nm                                                                           clear error  -> clear error
    TableMaterials wavelengths () (empty)                                                                      clear error  -> clear error
    DesignConfig lr_d -1                                                                                       clear error  -> clear error
    DesignConfig lr_k NaN                                                                                      clear error  -> clear error
    DesignConfig lr_m -1                                                                                       clear error  -> clear error
    DesignConfig population 0                                                                                  clear error  -> clear error
    DesignConfig polish_rings 0 (control: the rings of the stages)                                             ok           -> ok
    DesignConfig polish_rings -1                                                                               clear error  -> clear error
    DesignConfig tolerance_nominal_weight 2                                                                    clear error  -> clear error
    DesignConfig image_spp 0                                                                                   clear error  -> clear error
    design on_nonfinite 'warnn'                                                                                clear error  -> clear error

Run: PYTHONPATH=$PWD python tools/audit32a_probe.py [filter]
"""

import dataclasses
import os
import sys

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probe_table import FILTER, ROWS, jitted, mention_counts, probe, run, warned  # noqa: E402

import jaxlens as jl  # noqa: E402
import jaxlens.analysis as A  # noqa: E402
import jaxlens.design as D  # noqa: E402
from jaxlens import nets, zoo  # noqa: E402
from jaxlens import tracing as T  # noqa: E402

KEY = jax.random.PRNGKey(0)


def count_mentions(top=200):
    """The exported names named least in every probe and test file (round 31 included)."""
    mention_counts(lambda f: "32a" in f, top)


def expect(name, fn, want):
    """A row: "silent wrong" where ``fn()`` (text) does not start with ``want`` (the true answer)."""
    if FILTER and FILTER not in name:
        return
    try:
        got = str(fn())
    except Exception as e:  # noqa: BLE001
        ROWS.append((name, "crash", f"{type(e).__name__}: {e}"[:150]))
        return
    ROWS.append((name, "ok" if got.startswith(want) else "silent wrong", got[:100]))


def same_answer(name, fn, reference):
    """A row: "silent wrong" where ``fn()`` differs from ``reference()`` (the same input in
    the form the call expects), "ok" where they agree."""
    if FILTER and FILTER not in name:
        return
    try:
        diff = float(jnp.max(jnp.abs(jnp.asarray(fn(), float) - jnp.asarray(reference(), float))))
    except Exception as e:  # noqa: BLE001
        ROWS.append((name, "crash", f"{type(e).__name__}: {e}"[:150]))
        return
    ROWS.append((name, "silent wrong" if diff > 1e-9 else "ok", f"max difference {diff:.3g}"))


# ----------------------------------------------------------------------------- zoo and nets
def zoo_nets():
    probe("double_gauss clip 'no'", lambda: zoo.double_gauss(clip="no"), "clip")
    probe("cellphone6 clip 0", lambda: zoo.cellphone6(clip=0), "clip")
    probe("double_gauss clip False (control)", lambda: zoo.double_gauss(clip=False).epd, good=True)
    probe("Conv c_in 0", lambda: nets.Conv(0, 4, 3, key=KEY), "c_in")
    probe("Conv kernel 2.5", lambda: nets.Conv(3, 4, 2.5, key=KEY), "kernel")
    probe("Conv stride 2 with kernel 3", lambda: nets.Conv(3, 4, 3, stride=2, key=KEY), "stride")
    probe("Conv key 0 (an int)", lambda: nets.Conv(3, 4, 3, key=0), "key")
    probe("Conv dtype int32", lambda: nets.Conv(3, 4, 3, key=KEY, dtype=jnp.int32).weight, "dtype")
    probe("Conv called on 2 channels (built for 3)", lambda: nets.Conv(3, 4, 3, key=KEY)(jnp.ones((8, 8, 2))), "3")
    probe("Conv called on [8, 8] (no channel axis)", lambda: nets.Conv(1, 4, 3, key=KEY)(jnp.ones((8, 8))), "[H, W")
    probe("Conv kernel 4 stride 1 (even 'SAME')", lambda: nets.Conv(3, 4, 4, key=KEY), "kernel")
    probe("Conv 3x3 (control)", lambda: nets.Conv(3, 4, 3, key=KEY)(jnp.ones((8, 8, 3))).shape, good=True)
    probe("Pointwise c_out 10**9", lambda: nets.Pointwise(3, 10**9, key=KEY), "c_out")
    probe("Pointwise c_in -4", lambda: nets.Pointwise(-4, 4, key=KEY), "c_in")
    probe("Pointwise dtype int32", lambda: nets.Pointwise(3, 4, key=KEY, dtype=jnp.int32).weight, "dtype")
    probe("Pointwise called on 2 channels (built for 3)", lambda: nets.Pointwise(3, 4, key=KEY)(jnp.ones((8, 8, 2))), "3")
    probe("Depthwise channels 0", lambda: nets.Depthwise(0, key=KEY), "channels")
    probe("Depthwise called on 1 channel (built for 3)", lambda: nets.Depthwise(3, key=KEY)(jnp.ones((8, 8, 1))).shape, "3")
    probe("Depthwise called on [8, 8]", lambda: nets.Depthwise(3, key=KEY)(jnp.ones((8, 8))), "[H, W")
    probe("LayerNorm2d eps 0", lambda: nets.LayerNorm2d(3, eps=0.0), "eps")
    probe("LayerNorm2d eps NaN", lambda: nets.LayerNorm2d(3, eps=np.nan), "eps")
    probe("LayerNorm2d called on 1 channel (built for 3)", lambda: nets.LayerNorm2d(3)(jnp.ones((8, 8, 1))).shape, "3")
    probe("LayerNorm2d dtype int32", lambda: nets.LayerNorm2d(3, dtype=jnp.int32).weight, "dtype")
    probe("simple_gate 3 channels", lambda: nets.simple_gate(jnp.ones((4, 4, 3))), "even")
    probe("simple_gate a scalar", lambda: nets.simple_gate(jnp.ones(())), "even")
    probe("NAFBlock channels 0", lambda: nets.NAFBlock(0, key=KEY), "channels")
    probe("NAFBlock ffn_expand 0", lambda: nets.NAFBlock(4, ffn_expand=0, key=KEY), "ffn_expand")
    probe("NAFBlock dw_expand 2.5", lambda: nets.NAFBlock(4, dw_expand=2.5, key=KEY), "dw_expand")
    probe("NAFBlock dw_expand 10**6", lambda: nets.NAFBlock(4, dw_expand=10**6, key=KEY), "dw_expand")
    probe("NAFBlock called on 3 channels (built for 4)", lambda: nets.NAFBlock(4, key=KEY)(jnp.ones((8, 8, 3))), "4")
    probe("NAFBlock dtype int32", lambda: nets.NAFBlock(4, key=KEY, dtype=jnp.int32), "dtype")
    probe("Upsample c_in 3 (odd)", lambda: nets.Upsample(3, key=KEY), "c_in")
    probe("Upsample called on 2 channels (built for 4)", lambda: nets.Upsample(4, key=KEY)(jnp.ones((4, 4, 2))), "4")
    probe("NAFNet identity_init 'no'", lambda: nets.NAFNet(width=4, key=KEY, identity_init="no"), "identity_init")
    probe("NAFNet identity_init 0", lambda: nets.NAFNet(width=4, key=KEY, identity_init=0), "identity_init")
    probe("NAFNet in_channels 0", lambda: nets.NAFNet(0, 0, width=4, key=KEY), "in_channels")
    probe("NAFNet in_channels 1, out_channels 3", lambda: nets.NAFNet(1, 3, width=4, key=KEY), "out_channels")
    probe("NAFNet enc_blocks (1, 1), dec_blocks (1, 1, 1)", lambda: nets.NAFNet(width=4, enc_blocks=(1, 1), key=KEY), "dec_blocks")
    probe("NAFNet enc_blocks () dec_blocks () (control: no levels)", lambda: nets.NAFNet(width=4, enc_blocks=(), dec_blocks=(), key=KEY)(jnp.ones((5, 5, 3))).shape, good=True)
    probe("NAFNet enc_blocks 2 (an int)", lambda: nets.NAFNet(width=4, enc_blocks=2, dec_blocks=2, key=KEY), "enc_blocks")
    probe("NAFNet width 2.5", lambda: nets.NAFNet(width=2.5, key=KEY), "width")
    probe("NAFNet dtype int32", lambda: nets.NAFNet(width=4, key=KEY, dtype=jnp.int32), "dtype")
    net = nets.NAFNet(width=4, enc_blocks=(1,), dec_blocks=(1,), key=KEY)
    probe("NAFNet image [8, 8] (no channel axis)", lambda: net(jnp.ones((8, 8))), "[H, W")
    probe("NAFNet image [2, 8, 8, 3] (a batch)", lambda: net(jnp.ones((2, 8, 8, 3))), "[H, W")
    plain = nets.NAFNet(width=4, enc_blocks=(1,), dec_blocks=(1,), key=KEY, identity_init=False)
    ramp = jnp.arange(192).reshape(8, 8, 3)
    same_answer("NAFNet image int 0..191 (against the same image as floats)", lambda: plain(ramp), lambda: plain(ramp.astype(float)))
    same_answer("Conv called on an int image (against floats)", lambda: plain.intro(ramp), lambda: plain.intro(ramp.astype(float)))
    block = nets.NAFBlock(4, key=KEY)
    block = eqx.tree_at(lambda b: (b.beta, b.gamma), block, (jnp.full(4, 0.7), jnp.full(4, 0.3)))
    same_answer("NAFBlock (trained scales) called on an int image (against floats)", lambda: block(ramp[:, :, :1].repeat(4, -1)), lambda: block(ramp[:, :, :1].repeat(4, -1).astype(float)))
    probe("NAFNet image bool", lambda: net(jnp.ones((8, 8, 3), bool)), "image")
    probe("NAFNet image complex", lambda: net(jnp.ones((8, 8, 3), complex)), "image")
    probe("NAFNet image NaN", lambda: net(jnp.full((8, 8, 3), np.nan)), "image")
    probe("NAFNet image NaN under jit", jitted(lambda x: net(x), jnp.full((8, 8, 3), np.nan)), "image")
    probe("NAFNet image 1x1 (control: padded by repeating it)", lambda: net(jnp.ones((1, 1, 3))).shape, good=True)
    probe("NAFNet image 8x8 (control)", lambda: net(jnp.ones((8, 8, 3))).shape, good=True)
    probe("num_parameters None", lambda: nets.num_parameters(None), "model")
    probe("num_parameters a NAFNet (control)", lambda: nets.num_parameters(net), good=True)


# ----------------------------------------------------------------------------- analysis
def analysis():
    lens = zoo.cooke_triplet()
    probe("radius_for_fraction fraction 80 (percent)", lambda: A.radius_for_fraction(lens, 0.0, 80.0), "fraction")
    probe("radius_for_fraction fraction 1.0", lambda: A.radius_for_fraction(lens, 0.0, 1.0), "fraction")
    probe("radius_for_fraction fraction 80 under jit", jitted(lambda f: A.radius_for_fraction(lens, 0.0, f), 80.0), "fraction")
    probe("radius_for_fraction fraction [0.5, 0.8] (control)", lambda: A.radius_for_fraction(lens, 0.0, [0.5, 0.8]), good=True)
    probe("zernike_nm j 0 (Noll starts at 1)", lambda: A.zernike_nm(0), "j")
    probe("zernike_nm j -1", lambda: A.zernike_nm(-1), "j")
    probe("zernike_nm j 2.5", lambda: A.zernike_nm(2.5), "j")
    probe("zernike_nm j True", lambda: A.zernike_nm(True), "j")
    probe("zernike_nm j 10**12", lambda: A.zernike_nm(10**12), "j")
    probe("zernike_nm j 0 indexing 'ansi' (control: piston)", lambda: A.zernike_nm(0, indexing="ansi"), good=True)
    probe("zernike_nm indexing 'nol'", lambda: A.zernike_nm(4, indexing="nol"), "noll")
    sd = A.seidel(lens)
    probe("Seidel.wavefront per_surface 'no'", lambda: sd.wavefront(per_surface="no"), "per_surface")
    probe("Seidel.wavefront per_surface 0", lambda: sd.wavefront(per_surface=0), "per_surface")
    wf = A.wavefront(lens, 0.0, grid=17)
    probe("Wavefront.zernike terms 0", lambda: wf.zernike(terms=0).coefficients, "terms")
    probe("Wavefront.zernike terms 10**6", lambda: wf.zernike(terms=10**6).coefficients, "terms")
    probe("Wavefront.zernike terms 2.5", lambda: wf.zernike(terms=2.5).coefficients, "terms")
    probe("Wavefront.zernike indexing 'nol'", lambda: wf.zernike(indexing="nol").coefficients, "noll")
    probe("Wavefront.zernike terms 11 (control)", lambda: wf.zernike(terms=11).residual_rms, good=True)
    probe("angular_magnification wavelength 587.6 (nm)", lambda: A.angular_magnification(lens, 587.6), "nm")
    probe("angular_magnification wavelength NaN", lambda: A.angular_magnification(lens, np.nan), "wavelength")
    probe("chief_ray field 100 (deg)", lambda: A.chief_ray(lens, 100.0).origin, "field")
    probe("chief_ray field NaN", lambda: A.chief_ray(lens, np.nan).origin, "field")
    probe("chief_ray field [0, 5, 10] (several)", lambda: A.chief_ray(lens, jnp.array([0.0, 5.0, 10.0])).origin, "field")
    probe("chief_ray field NaN under jit", jitted(lambda f: A.chief_ray(lens, f).origin, np.nan), "field")
    probe("chief_ray field 100 under jit", jitted(lambda f: A.chief_ray(lens, f).origin, 100.0), "field")
    probe("chief_ray depth 0", lambda: A.chief_ray(lens, 5.0, depth=0.0).origin, "depth")
    probe("chief_ray aim 'reel'", lambda: A.chief_ray(lens, 5.0, aim="reel").origin, "aim")
    probe("spot_rays pupil [5, 3] (3 coordinates)", lambda: A.spot_rays(lens, 5.0, pupil=jnp.zeros((5, 3))).origin, "pupil")
    probe("spot_rays pupil [] (no points)", lambda: A.spot_rays(lens, 5.0, pupil=jnp.zeros((0, 2))).origin, "pupil")
    probe("spot_rays pupil (1.5, 0) (outside the unit pupil)", lambda: A.spot_rays(lens, 5.0, pupil=jnp.array([[1.5, 0.0]])).valid, "pupil")
    probe("spot_rays pupil complex", lambda: A.spot_rays(lens, 5.0, pupil=jnp.zeros((4, 2), complex)).origin, "pupil")
    probe("spot_rays pupil NaN under jit", jitted(lambda q: A.spot_rays(lens, 5.0, pupil=q).origin, jnp.full((4, 2), np.nan)), "pupil")
    probe("opd pupil shape (3,)", lambda: A.opd(lens, 5.0, jnp.zeros(3)), "pupil")
    probe("opd pupil (2, 0) (outside the unit pupil)", lambda: A.opd(lens, 5.0, jnp.array([2.0, 0.0])), "pupil")
    probe("opd pupil NaN", lambda: A.opd(lens, 5.0, jnp.array([np.nan, 0.0])), "pupil")
    probe("opd reference 'spherical'", lambda: A.opd(lens, 5.0, jnp.zeros(2), reference="spherical"), "reference")
    probe("opd pupil (0.3, 0.4) (control)", lambda: A.opd(lens, 5.0, jnp.array([0.3, 0.4])), good=True)
    probe("opd_fan n 0", lambda: A.opd_fan(lens, 5.0, n=0).tangential, "n")
    probe("opd_fan n 10**8", lambda: A.opd_fan(lens, 5.0, n=10**8).tangential, "n")
    probe("opd_fan n 1", lambda: A.opd_fan(lens, 5.0, n=1).tangential, "n")
    probe("opd_fan wavelengths () (empty)", lambda: A.opd_fan(lens, 5.0, ()).tangential, "wavelengths")
    probe("ray_fan n 2.5", lambda: A.ray_fan(lens, 5.0, n=2.5).tangential, "n")
    probe("ray_fan wavelengths [] (empty)", lambda: A.ray_fan(lens, 5.0, []).tangential, "wavelengths")
    probe("ray_fan field (0, 5, 10)", lambda: A.ray_fan(lens, (0.0, 5.0, 10.0)).tangential, "field")
    probe("ray_fan wavelengths [486.1, 587.6] (nm)", lambda: A.ray_fan(lens, 5.0, [486.1, 587.6]).tangential, "nm")
    probe("field_curvature fields () (empty)", lambda: A.field_curvature(lens, ()).tangential, "fields")
    probe("distortion fields [] (empty)", lambda: A.distortion(lens, []).percent_ftan, "fields")
    probe("rms_spot fields () (empty)", lambda: A.rms_spot(lens, fields=()).polychromatic, "fields")
    probe("rms_spot wavelengths () (empty)", lambda: A.rms_spot(lens, wavelengths=()).polychromatic, "wavelengths")
    probe("angular_spot fields () (empty)", lambda: A.angular_spot(lens, fields=()).polychromatic, "fields")
    probe("clear_semi_diameters fields () (empty)", lambda: A.clear_semi_diameters(lens, fields=()), "fields")
    probe("clear_semi_diameters n_rim 0", lambda: A.clear_semi_diameters(lens, n_rim=0), "n_rim")
    probe("clear_semi_diameters reaching 'yes'", lambda: A.clear_semi_diameters(lens, reaching="yes"), "reaching")
    probe("rms_spot pupil (1.5, 0) (outside the unit pupil)", lambda: A.rms_spot(lens, pupil=jnp.array([[0.0, 0.0], [1.5, 0.0]])).polychromatic, "pupil")
    probe("spot_rays pupil (1.5, 0) under jit", jitted(lambda q: A.spot_rays(lens, 5.0, pupil=q).valid, jnp.array([[1.5, 0.0]])), "pupil")
    probe("spot_rays pupil hexapolar (control)", lambda: A.spot_rays(lens, 5.0, pupil=jl.sampling.pupil_hexapolar(3)).valid.sum(), good=True)


# ----------------------------------------------------------------------------- tracing and lenses
def tracing_lenses():
    lens = zoo.cooke_triplet()
    rays = jl.sampling.collimated(lens, 0.0, jl.sampling.pupil_grid(3))
    probe("trace_path uniform 'no'", lambda: jl.trace_path(lens, rays, uniform="no").origin, "uniform")
    probe("trace_path upto 0 (control: surface 1, 0-based)", lambda: jl.trace_path(lens, rays, upto=0).origin.shape, good=True)
    probe("trace_path upto 99", lambda: jl.trace_path(lens, rays, upto=99).origin, "upto")
    probe("trace_backward upto 99", lambda: jl.trace_backward(lens, rays, upto=99).origin, "upto")
    probe("reversed_lens image_distance NaN", lambda: T.reversed_lens(lens, image_distance=np.nan).thickness, "image_distance")
    probe("reversed_lens image_distance -5 (control: an image before the last surface)", lambda: T.reversed_lens(lens, image_distance=-5.0).thickness, good=True)
    probe("reversed_lens image_distance '10'", lambda: T.reversed_lens(lens, image_distance="10").thickness, "image_distance")
    probe("reversed_lens (control)", lambda: T.reversed_lens(lens).thickness, good=True)
    probe("Hybrid odd_x NaN", lambda: jl.Hybrid(odd_x=(np.nan, 0.0, 0.0, 0.0)), "odd_x")
    probe("Hybrid odd_y 2-D", lambda: jl.Hybrid(odd_y=jnp.zeros((2, 2))).odd_y, "odd_y")
    probe("Biconic kx NaN", lambda: jl.Biconic(kx=np.nan), "kx")
    probe("Biconic cx inf", lambda: jl.Biconic(cx=np.inf), "cx")
    probe("Aperture shape 'rectangle'", lambda: jl.Aperture("rectangle", 1.0, 1.0), "rect")
    probe("Aperture half_x -1", lambda: jl.Aperture("rect", -1.0, 1.0), "half_x")
    probe("Aperture half_y 0", lambda: jl.Aperture("rect", 1.0, 0.0), "half_y")
    probe("Aperture blocks 'no'", lambda: jl.Aperture("circle", 1.0, 1.0, blocks="no"), "blocks")
    probe("Aperture decenter_x NaN", lambda: jl.Aperture("circle", 1.0, 1.0, decenter_x=np.nan), "decenter_x")
    probe("TiltedPlane tan_x 45 (degrees)", warned(lambda: jl.TiltedPlane(tan_x=45.0)), "tan_x")
    probe("Stop semi_diameter -1", lambda: jl.Stop(semi_diameter=-1.0), "semi_diameter")
    probe("Plane semi_diameter NaN", lambda: jl.Plane(semi_diameter=np.nan), "semi_diameter")
    probe("QTypeAsphere qtype 'bfs2'", lambda: jl.QTypeAsphere(qtype="bfs2"), "bfs")
    probe("QTypeAsphere norm_radius 0", lambda: jl.QTypeAsphere(norm_radius=0.0), "norm_radius")
    probe("Binary2 norm_radius 0", lambda: jl.Binary2(norm_radius=0.0), "norm_radius")
    probe("Binary2 order NaN", lambda: jl.Binary2(order=np.nan), "order")
    probe("ZernikeSag norm_radius -1", lambda: jl.ZernikeSag(norm_radius=-1.0), "norm_radius")
    probe("ZernikeSag ordering 'fringe2'", lambda: jl.ZernikeSag(ordering="fringe2"), "fringe")
    probe("ZernikeSag extrapolate 'no'", lambda: jl.ZernikeSag(extrapolate="no"), "extrapolate")
    probe("CoordinateBreak order 2", lambda: jl.CoordinateBreak(order=2), "order")
    probe("CoordinateBreak tilt_x NaN", lambda: jl.CoordinateBreak(tilt_x=np.nan), "tilt_x")
    mk = lambda **k: jl.Lens(surfaces=(jl.Sphere(1 / 30.0), jl.Sphere(-1 / 45.0)), thickness=jnp.array([6.0, 33.4]),
                             materials=(jl.get_material("N-BK7"), jl.Air()), epd=10.0, **({"fields": jnp.array([0.0, 10.0])} | k))
    probe("Lens stop on the last surface (control)", lambda: float(jl.efl(mk(stop=1))), good=True)
    probe("Lens stop 2 of 2 surfaces", lambda: mk(stop=2), "stop")
    probe("Lens object_distance 1e-3 (control: a finite object 1 µm away)", lambda: A.rms_spot(mk(object_distance=1e-3, fields=jnp.array([0.0, 0.01]))).polychromatic, good=True)
    probe("Lens object_distance 0", lambda: mk(object_distance=0.0), "object_distance")
    probe("Lens object_distance -10", lambda: mk(object_distance=-10.0), "object_distance")
    probe("Lens thickness [0, 33.4] (zero-thickness glass; control)", lambda: float(jl.efl(dataclasses.replace(mk(), thickness=jnp.array([0.0, 33.4])))), good=True)
    probe("Lens mirrors (5,) (out of range)", lambda: mk(mirrors=(5,)), "mirrors")
    probe("Lens mirrors (0, 0) (twice)", lambda: mk(mirrors=(0, 0)), "mirrors")
    probe("Lens obscurations {0: 20} (larger than the EPD)", lambda: mk(obscurations={0: 20.0}), "obscuration")
    probe("Lens fields [0, 10] rad-looking (0.1745)", warned(lambda: mk(fields=jnp.array([0.0, 0.17453292519943295]))), "radian")
    probe("Lens epd NaN in a traced lens (control: NaN spots, not re-checked under jit as documented)", jitted(lambda e: A.rms_spot(dataclasses.replace(mk(), epd=e)).polychromatic, np.nan), good=True)
    probe("Lens fields as ints [0, 10] (control)", lambda: A.rms_spot(mk(fields=jnp.array([0, 10]))).polychromatic, good=True)
    probe("Lens wavelengths [0.5876] as a tuple (control)", lambda: float(jl.efl(mk(wavelengths=(0.5876,)))), good=True)
    probe("Lens wavelengths () (empty)", lambda: mk(wavelengths=()), "wavelengths")
    probe("Lens fields () (empty)", lambda: mk(fields=()), "fields")
    probe("Lens fields [[0, 5, 1]] (3 per field)", lambda: mk(fields=jnp.array([[0.0, 5.0, 1.0]])), "fields")
    probe("Lens fields complex", lambda: mk(fields=jnp.array([0.0, 10.0], complex)), "fields")
    probe("Lens primary 1.0 (float)", lambda: mk(wavelengths=(0.4861, 0.5876), primary=1.0).primary, "primary")
    probe("Lens primary True", lambda: mk(wavelengths=(0.4861, 0.5876), primary=True).primary, "primary")


# ----------------------------------------------------------------------------- unusual lenses
def unusual_lenses():
    from jaxlens.optics.coordinates import CoordinateBreak

    def mirror(t=-100.0, **k):
        return jl.Lens(surfaces=(jl.Conic(-1 / 200.0, -1.0),), thickness=jnp.array([t]), materials=(jl.Air(),),
                       epd=20.0, fields=jnp.array([0.0, 0.5]), mirrors=(0,), **k)
    m = mirror()
    geometry = lambda lens: (lambda g: f"ok {bool(g.ok)}, min_gap {[round(float(x), 3) for x in g.min_gap]}")(A.self_intersection(lens))
    expect("self_intersection a concave mirror, image 100 mm before it (true: no crossing)", lambda: geometry(m), "ok True")
    expect("self_intersection a mirror whose image plane cuts its rim (true: crossing; control)", lambda: geometry(mirror(-0.01)), "ok False")
    cass = jl.Lens(surfaces=(jl.Conic(-1 / 200.0, -1.0), jl.Sphere(-1 / 80.0)), thickness=jnp.array([-60.0, 90.0]),
                   materials=(jl.Air(), jl.Air()), epd=20.0, fields=jnp.array([0.0, 0.2]), mirrors=(0, 1))
    expect("self_intersection a Cassegrain, secondary 60 mm before the primary (true: no crossing)", lambda: geometry(cass), "ok True")
    probe("efl of a concave mirror R -200 (control: 100)", lambda: float(jl.efl(m)), good=True)
    probe("rms_spot of a paraboloid on axis (control: 0)", lambda: A.rms_spot(m).polychromatic, good=True)
    probe("render a mirror lens", lambda: jl.render(dataclasses.replace(m, sensor=jl.Sensor((8, 8), 0.01)), jnp.ones((8, 8, 3)), spp=1, key=KEY), "mirrors")
    tilt = jl.Lens(surfaces=(jl.Sphere(1 / 30.0), CoordinateBreak(tilt_x=5.0), jl.Sphere(-1 / 45.0)), thickness=jnp.array([6.0, 0.0, 33.4]),
                   materials=(jl.get_material("N-BK7"), jl.get_material("N-BK7"), jl.Air()), epd=10.0, fields=jnp.array([0.0, 5.0]))
    probe("seidel of a lens with a 5° coordinate break", lambda: A.seidel(tilt).wavefront(), "coordinate")
    probe("rms_spot of a lens with a 5° coordinate break (control)", lambda: A.rms_spot(tilt).polychromatic, good=True)
    cooke = zoo.cooke_triplet()
    probe("rms_spot fields and wavelengths swapped", lambda: A.rms_spot(cooke, fields=cooke.wavelengths, wavelengths=cooke.fields).polychromatic, "wavelength")
    probe("psf pixel_size 5 (µm)", lambda: jl.psf(cooke, 0.0, pixel_size=5.0, kernel_size=9), "pixel_size")
    probe("psf field 0.349 (20° in radians)", warned(lambda: jl.psf(cooke, 0.3490658503988659, pixel_size=0.002, kernel_size=9)), "radian")
    probe("wavefront field and wavelength swapped (0.5876, 14; wavelength is keyword-only)", lambda: A.wavefront(cooke, 0.5876, 14.0).rms, "positional")
    probe("wavefront field 0.349 (20° in radians)", warned(lambda: A.wavefront(cooke, 0.3490658503988659, grid=9).rms), "radians")
    probe("opd field 0.349 (20° in radians)", warned(lambda: A.opd(cooke, 0.3490658503988659, jnp.zeros(2))), "radians")
    probe("opd_fan field 0.349 (20° in radians)", warned(lambda: A.opd_fan(cooke, 0.3490658503988659, n=5).tangential), "radians")
    probe("wavefront field 0.1745 (10° in radians)", warned(lambda: A.wavefront(cooke, 0.17453292519943295, grid=9).rms), "radians")
    probe("wavefront field 14 (control)", warned(lambda: A.wavefront(cooke, 14.0, grid=9).rms), good=True)
    probe("encircled_energy method 'geometric' with pupil_side 1 (a diffraction setting; refused whatever the method)", lambda: A.encircled_energy(cooke, 0.0, [0.01], pupil_side=1).energy, "pupil_side")


# ----------------------------------------------------------------------------- design
def design():
    spec = D.DesignSpec()
    probe("paper_stages final_loss 'imag'", lambda: D.paper_stages(spec, final_loss="imag"), "final_loss")
    probe("paper_stages n -1", lambda: D.paper_stages(spec, n=-1), "n")
    probe("paper_stages polish 'LM' (polish_steps 10)", lambda: D.paper_stages(spec, polish="LM", polish_steps=10), "polish")
    probe("paper_stages solver 'Adam'", lambda: D.paper_stages(spec, solver="Adam"), "solver")
    probe("paper_stages polish 'lm' polish_steps 10 (control)", lambda: len(D.paper_stages(spec, polish_steps=10)), good=True)
    probe("paper_stages pin -1", lambda: D.paper_stages(spec, pin=-1.0), "pin")
    probe("sensor_field_grid n 0", lambda: D.sensor_field_grid(spec, 0), "n")
    probe("sensor_field_grid n 10**6", lambda: D.sensor_field_grid(spec, 10**6), "n")
    probe("sine_path n 0 (control: one stage at the end, documented)", lambda: D.sine_path(0.0, 1.0, 0), good=True)
    probe("sine_path start NaN", lambda: D.sine_path(np.nan, 1.0, 3), "start")
    probe("sine_path n 10**10", lambda: D.sine_path(0.0, 1.0, 10**10), "n")
    probe("random_params key 0 (an int)", lambda: D.random_params(spec, 0).c, "key")
    probe("random_params dtype int32", lambda: D.random_params(spec, KEY, dtype=jnp.int32).c, "dtype")
    probe("random_starts seeds [] (none)", lambda: D.random_starts(spec, []).c, "seeds")
    probe("random_starts seeds [1, 1] (control: design pads a device batch with repeats)", lambda: D.random_starts(spec, [1, 1]).c.shape, good=True)
    probe("random_starts seeds -1", lambda: D.random_starts(spec, [-1]).c, "seed")
    probe("random_starts seeds 10**6 (a count?)", lambda: D.random_starts(spec, 10**6).c, "seeds")
    lens = zoo.cellphone6()
    ev_spec = D.DesignSpec(fov=80.8, fnum=2.0)
    probe("evaluate_design min_valid 99 (percent)", lambda: D.evaluate_design(lens, ev_spec, min_valid=99.0).rays_ok, "min_valid")
    probe("evaluate_design min_valid NaN", lambda: D.evaluate_design(lens, ev_spec, min_valid=np.nan).rays_ok, "min_valid")
    probe("evaluate_design n 0", lambda: D.evaluate_design(lens, ev_spec, n=0).rays_ok, "n")
    probe("DampedLeastSquares lam0 0", lambda: D.DampedLeastSquares(lambda p: p.c, lam0=0.0), "lam0")
    probe("DampedLeastSquares lam0 NaN", lambda: D.DampedLeastSquares(lambda p: p.c, lam0=np.nan), "lam0")
    probe("DampedLeastSquares inner 0", lambda: D.DampedLeastSquares(lambda p: p.c, inner=0), "inner")
    probe("DampedLeastSquares residual_fn None", lambda: D.DampedLeastSquares(None), "residual_fn")
    probe("LevenbergMarquardt rtol -1", lambda: D.LevenbergMarquardt(lambda p: p.c, rtol=-1.0), "rtol")
    probe("LevenbergMarquardt atol NaN", lambda: D.LevenbergMarquardt(lambda p: p.c, atol=np.nan), "atol")
    probe("LevenbergMarquardt free 'all'", lambda: D.LevenbergMarquardt(lambda p: p.c, free="all"), "free")
    probe("catalog_names obsolete 'no'", lambda: jl.catalog_names("SCHOTT", obsolete="no"), "obsolete")
    probe("catalog_names catalog 'schot'", lambda: jl.catalog_names("schot"), "SCHOTT")
    probe("catalog_names catalogs [] (none)", lambda: jl.catalog_names(catalogs=[]), "catalogs")
    probe("catalog_names catalog and catalogs both", lambda: jl.catalog_names("SCHOTT", catalogs=["CDGM"]), "catalog")
    probe("CatalogMaterial catalog_vd NaN", lambda: jl.CatalogMaterial(jl.ModelGlass(1.5, 60.0), "G", catalog_vd=np.nan), "catalog_vd")
    probe("CatalogMaterial catalog_nd 60, catalog_vd 1.5 (swapped)", lambda: jl.CatalogMaterial(jl.ModelGlass(1.5, 60.0), "G", catalog_nd=60.0, catalog_vd=1.5), "catalog_nd")
    probe("CatalogMaterial formula 99", lambda: jl.CatalogMaterial(jl.ModelGlass(1.5, 60.0), "G", formula=99), "formula")
    probe("CatalogMaterial name 5", lambda: jl.CatalogMaterial(jl.ModelGlass(1.5, 60.0), 5), "name")
    probe("CatalogMaterial model None", lambda: jl.CatalogMaterial(None, "G"), "model")
    probe("CatalogMaterial wavelength_range (365, 2325) (nm)", lambda: jl.CatalogMaterial(jl.ModelGlass(1.5, 60.0), "G", wavelength_range=(365.0, 2325.0)), "nm")
    probe("TableMaterials wavelengths in nm", lambda: D.TableMaterials([486.1, 587.6, 656.3]), "nm")
    probe("TableMaterials wavelengths () (empty)", lambda: D.TableMaterials(()), "wavelengths")
    probe("DesignConfig lr_d -1", lambda: D.DesignConfig(lr_d=-1.0), "lr_d")
    probe("DesignConfig lr_k NaN", lambda: D.DesignConfig(lr_k=np.nan), "lr_k")
    probe("DesignConfig lr_m -1", lambda: D.DesignConfig(lr_m=-1.0), "lr_m")
    probe("DesignConfig population 0", lambda: D.DesignConfig(population=0), "population")
    probe("DesignConfig polish_rings 0 (control: the rings of the stages)", lambda: D.DesignConfig(polish_rings=0).polish_rings, good=True)
    probe("DesignConfig polish_rings -1", lambda: D.DesignConfig(polish_rings=-1), "polish_rings")
    probe("DesignConfig tolerance_nominal_weight 2", lambda: D.DesignConfig(tolerance_nominal_weight=2.0), "tolerance_nominal_weight")
    probe("DesignConfig image_spp 0", lambda: D.DesignConfig(image_spp=0), "image_spp")
    probe("design on_nonfinite 'warnn'", lambda: D.design(spec, [0], on_nonfinite="warnn", progress=False), "on_nonfinite")


if os.environ.get("AUDIT32A_COUNT"):
    count_mentions()
else:
    run([zoo_nets, analysis, tracing_lenses, unusual_lenses, design])
