"""Zemax OpticStudio sequential lens files (``.zmx``), read and write.

Conventions:
    Zemax numbers surfaces from 0 (the object) to N (the image); ``Lens.surfaces[i]`` is
    Zemax surface i + 1. Lengths are converted to mm from the file's ``UNIT`` (MM, CM, IN
    or METER), wavelengths are in µm as in Zemax, field angles in degrees.

What is read and written:
    * ``TYPE STANDARD`` (CURV, CONI; a block without TYPE, but not one with non-zero
      PARM/XDAT, which is refused as a missing TYPE line), ``TYPE EVENASPH``
      (PARM 1..8 = A2, A4, …, A16, so
      PARM 1 multiplies r²), ``TYPE XASPHERE`` (extended asphere: XDAT 1 = number of
      terms, XDAT 2 = normalisation radius, XDAT 3… = the r², r⁴, … coefficients; used
      for even aspheres with more than 8 terms) and ``TYPE ODDASPHE`` (an ``OddAsphere``:
      PARM 1..8 = β_1 … β_8 on r, r², …, r⁸; a nonzero PARM beyond 8 is refused); ``TYPE
      XOSPHERE`` (extended odd asphere, an ``OddAsphere``: XDAT 1 = number of terms N ≤ 240,
      XDAT 2 = normalisation radius R, XDAT 3… = A_1 … A_N on (r/R)¹ … (r/R)ᴺ, so
      β_i = A_i / R^i; no PARM; an ``OddAsphere`` with more than 8 terms is written so, R = 1).
      ``TYPE TILTSURF`` (a
      ``TiltedPlane``, the plane z = tan θx·x + tan θy·y through the vertex: PARM 1 = tan θx,
      PARM 2 = tan θy, dimensionless; CURV, CONI, other PARMs and XDAT 0; the frame of the
      surfaces after it is unchanged, unlike COORDBRK). ``TYPE BINARY_2`` (a ``Binary2``,
      ``jaxlens.optics.diffractive``: CURV, CONI and PARM 1..8 the even asphere, PARM 0 the
      diffraction order M, XDAT 1 = number of phase terms N, XDAT 2 = normalisation radius R
      (lens units), XDAT 3.. = A_1 … A_N in radians on (r/R)², (r/R)⁴, …; phase terms without
      PARM 0, a mirror, and malformed XDAT lines are refused with the line). ``TYPE
      QED_TYPE`` (a Forbes Q-type asphere, ``QTypeAsphere``, ``jaxlens.optics.qtype``: CURV
      and CONI the base conic, XDAT 1 = 0 Q-bfs or 1 Q-con, XDAT 2 = number of terms N,
      XDAT 3 = normalisation radius, XDAT 4 … N+3 = a_0 … a_(N−1) in lens units; no PARM;
      malformed XDAT lines are refused with the line); ``TYPE
      DGRATING`` (a ``Grating``, ``jaxlens.optics.diffractive``: CURV, CONI the base conic,
      PARM 1 = line density T in lines per µm whatever the lens unit, PARM 2 = the whole
      diffraction order M, positive toward +y; transmissive, or reflective with GLAS MIRROR;
      a negative T, a fractional M, other PARMs or any XDAT refused with the line); ``TYPE
      BICONICX`` (a ``Biconic``, ``jaxlens.optics.freeform``: CURV, CONI the y–z section,
      PARM 1 the x radius (0: flat in x), PARM 2 the x conic); ``TYPE SZERNSAG``/``FZERNSAG``
      (a ``ZernikeSag``: an even asphere, PARM 1–8, plus Zernike Standard (Noll) or Fringe
      terms, XDAT 1 = N, XDAT 2 = normalisation radius, XDAT 3… the coefficients in lens
      units; PARM 0 the extrapolate flag, PARM 9, 10 the terms' decenter). The image
      surface may be STANDARD, EVENASPH, ODDASPHE or TILTSURF (a tilted image plane).
    * The hybrid surface (even asphere plus odd terms Σ b_j x^{2j+1} + d_j y^{2j+1}) is
      written as Zemax's extended polynomial, ``TYPE XPOLYNOM``: a conic plus Σ A_i E_i
      with E_i the monomials x^m y^n ordered by degree and, within a degree, by falling
      power of x (x, y, x², xy, y², x³, …); XDAT 1 = the number of terms, XDAT 2 = the
      normalisation radius (written as 1, so the coefficients are the sag coefficients
      in mm). The r^{2i} terms are expanded binomially, (x² + y²)^i. This is exact: Zemax
      computes the same sag. A surface comment ``jaxlens hybrid even=M odd=P`` keeps the
      number of even and odd coefficients so the round trip restores the same shapes;
      reading such a surface checks that the polynomial has that structure and raises
      otherwise. An ``XPOLYNOM`` without the comment is read as an ``XYPolynomial``
      (``jaxlens.optics.xypolynomial``: any of the 230 terms).
    * ``DISZ`` (INFINITY for the object), ``STOP``, ``DIAM`` (the semi-diameter), and the
      surface apertures, which are what clip rays, as in Zemax: the semi-diameter alone
      never does (a fixed ``DIAM`` with no aperture clips nothing). ``CLAP 0 r 0``
      (circular aperture) clips at r; ``FLAP 0 r 0`` (floating aperture, which Zemax adds
      where a user types a semi-diameter on a surface with power) clips at the DIAM value
      when that is fixed, and at nothing when DIAM is automatic (solve flag 0: the height
      of the file's outermost ray). A clipping semi-diameter is written as both
      ``DIAM r 1`` and ``CLAP 0 r 0``.
      ``OBSC r_min r_max`` (a circular obscuration, ``Lens.obscurations``) is read and
      written; an annular ``CLAP r_in r 0`` is the clipping radius r and an obscuration
      inside r_in. ``SQAP hx hy``/``ELAP hx hy`` (rectangular/elliptical apertures, half-widths)
      and ``SQOB``/``ELOB`` (rectangular/elliptical obscurations) are ``Lens.apertures``
      (``jaxlens.Aperture``), and so are CLAP and ``OBSC 0 r`` on a surface with an aperture
      decenter ``OBDC dx dy``, which moves every aperture of its surface. A surface with
      such apertures clips at them only. They are written
      back the same way (one OBDC per surface). Refused: a decentered annular OBSC, an OBDC
      on a surface whose only clipping is a floating aperture (FLAP; on a surface that
      clips nothing it is ignored), and a decentered or non-circular stop aperture under
      ``FLOA``.
    * ``TYPE COORDBRK`` (a ``CoordinateBreak``): PARM 1, 2 decenter x, y; PARM 3, 4, 5 tilt
      about x, y, z in degrees; PARM 6 the order flag (0 or 1); CURV 0; no GLAS (the
      medium continues). ``GLAS MIRROR`` makes a surface a mirror (``Lens.mirrors``); the
      medium after it is the one before, and the thicknesses after an odd number of
      mirrors are negative, as Zemax writes them. A fold whose breaks turn the frame round
      with the light (Quadoa's -45°, the mirror, +135° with a decenter, positive
      thicknesses) reads too: each medium's direction of travel comes from the frames
      (``Lens.travel_senses``, ``optics.travel``). A break that turns a frame across the
      light is refused with its line.
    * Image space is the last lens surface's GLAS; it is also written on the image
      surface (optiland reads image space there). An image-surface GLAS that differs
      gives a warning.
    * ``GLAS``: catalog glasses by name (``GLAS N-BK7 0 0 1.5168 6.417E+001 0 0 0 0 0 0``,
      with the catalog's nd and Vd), model glasses as Zemax writes them
      (``GLAS ___BLANK 1 0 nd Vd 0 0 0 0 0 0``), ``GCAT`` (the catalogs searched, in
      order; ``jaxlens.io.zmx_glass`` says what happens to a name they lack).
    * Glasses not in Zemax's own catalogs (user AGF glasses, index tables, the model
      dispersion of OKP4, materials of any other class) go into ``.AGF`` catalogs written
      beside the ``.zmx`` and listed first in ``GCAT``. Zemax reads them once copied into
      its ``glasscat`` folder; jaxlens reads them from beside the file. A glass whose
      dispersion no AGF formula holds exactly (an index table, most notably) gets the
      Schott formula through its data points (exact for up to 6 points, least squares
      beyond), and its exact definition in a ``GC jaxlens {...}`` comment record, which
      Zemax ignores and jaxlens reads back, so the round trip loses nothing.
    * ``ENPD`` (entrance pupil diameter), ``FNUM x 0`` (image-space F/# = EFL/EPD),
      ``FNUM x 1`` (paraxial working F/# = 1/(2n′u′), u′ the image-space marginal slope), ``FLOA``
      (float by stop size: the stop's CLAP or DIAM), ``OBNA x 0`` (object-space NA) and
      ``OBNA x 1`` (object cone angle, degrees), both read as EPD = 2·d·tan u with d the
      object-to-entrance-pupil distance; ``FTYP 0`` (angle fields), ``FTYP 1`` (object
      heights of a finite object, converted exactly to the angles whose object points lie
      there), ``FTYP 3`` (real image heights: the field whose real chief ray lands there,
      the chief ray as the file's ray aiming traces it, through the paraxial entrance
      pupil's centre with ``RAIM`` off, aimed at the stop's centre with it on) and
      ``FTYP 2`` (paraxial image heights,
      converted exactly to angles: θ = atan(h/K), K the paraxial image height per unit
      tan θ) with ``XFLN``/``YFLN`` (fields FTYP counts but
      ``YFLN`` omits are on axis, with a warning; older files' ``XFLD``/``YFLD``, one value a
      field, where there are no XFLN/YFLN); other field types, telecentric object
      space and afocal image space are refused. Vignetting factors (VDXN, VDYN, VCXN, VCYN,
      VANN) are read into ``Lens.vignetting`` and reshape each field's pupil
      (``jaxlens.imaging.sampling.field_rays``). ``PUPD`` beside another aperture line
      (older Zemax) is ignored; alone it is refused. ``RAIM``'s ray-aiming type is
      ``Lens.aim``: 0 (off) ``"paraxial"``, 1 (Zemax's "Paraxial": rays aimed at the stop,
      sized paraxially) ``"real"``, 2 (Zemax's "Real": the stop sized by the real
      on-axis marginal ray) ``"real_marginal"``; each is written back as its type. Under
      ``FLOA`` both aimed types fill the stop's semi-diameter (it is the aperture, given, as
      OpticStudio and optiland aim there), so 2 is read as ``"real"`` too
      (``zmx_system.float_by_stop_aim``). ``WAVM`` (or the
      older ``WAVL``) and ``PWAV``, ``UNIT``, ``NAME``. ``ENVD``: indices adjusted to an
      environment other than 20 °C and 1 atm are refused; not adjusted, a warning. A finite
      object must be a plane normal to the axis (a curved or tilted one is refused).
    * The sensor (``Lens.sensor``) is kept in the image surface's comment,
      ``COMM jaxlens sensor rows=480 cols=640 pixel=0.005``, which Zemax ignores.
    * Files are read as UTF-16 (with BOM, Zemax's default), UTF-32 (with BOM), UTF-8 (with
      or without BOM) or latin-1, and written as UTF-8.

    * Multi-configuration files (``MNUM`` and the operand rows after it): the surfaces are
      the active configuration, which is read by default; ``config=N`` reads configuration
      N (``jaxlens.io.zmx_config`` says which operands it applies and which it refuses);
      ``configurations(path)`` lists them. Written lenses have one configuration.

Malformed files raise ``ValueError`` naming the file, the line number and the line.
Everything else in a file (solves, pickups, tolerances, coatings, drawing settings) is
ignored on reading and not written.
"""

from __future__ import annotations

from .zmx_common import ZEMAX_CATALOGS as ZEMAX_CATALOGS
from .zmx_common import term_index as term_index
from .zmx_common import term_powers as term_powers
from .zmx_read import ZmxWarning as ZmxWarning
from .zmx_read import configurations as configurations
from .zmx_read import decode as decode
from .zmx_read import load_zmx as load_zmx
from .zmx_read import loads as loads
from .zmx_write import dumps as dumps
from .zmx_write import save_zmx as save_zmx
from .zmx_write import surface_lines as surface_lines
