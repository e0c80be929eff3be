"""Sample lenses built in code, from published prescriptions.

Every function returns a :class:`jaxlens.Lens` with its entrance pupil diameter, field
angles (degrees), the F, d and C wavelengths (µm, primary d), the aperture stop and, where it
makes sense, a :class:`jaxlens.Sensor`. Lengths are in mm. The numbers are public optical
prescriptions; each docstring names its source.

Semi-diameters (clear apertures) are set a little larger than the largest ray height that the
stated fields and the full entrance pupil reach, so the sample lenses do not vignette at their
own fields; pass ``clip=False`` for unclipped surfaces (``semi_diameter = inf``).

Example:
    >>> import jaxlens
    >>> lens = jaxlens.zoo.cooke_triplet()
    >>> round(float(jaxlens.efl(lens)), 3)
    50.022
"""

from __future__ import annotations

import jax.numpy as jnp

from .optics import checks
from .optics.lens import Lens, Sensor
from .optics.materials import (
    LAMBDA_C,
    LAMBDA_D,
    LAMBDA_F,
    AbstractMaterial,
    Air,
    ModelGlass,
    Tabulated,
)
from .optics.surfaces import EvenAsphere, Plane, Sphere, Stop

__all__ = ["cooke_triplet", "double_gauss", "cellphone6", "ZOO"]

FDC = (LAMBDA_F, LAMBDA_D, LAMBDA_C)


def _fdc(nf: float, nd: float, nc: float, name: str) -> Tabulated:
    """A glass given by its indices at the F, d and C lines."""
    return Tabulated(wavelengths=FDC, indices=(nf, nd, nc), name=name)


def _sd(value: float, clip: bool) -> float:
    checks.switch(clip, "clip", "zoo")
    return value if clip else float("inf")


def cooke_triplet(*, clip: bool = True) -> Lens:
    """Cooke triplet, f ≈ 50 mm, F/5, fields 0/14/20°, six spherical surfaces (SK16/F2/SK16).

    Source: the Cooke triplet sample of optiland 0.6.3
    (``optiland/samples/objectives.py::CookeTriplet``), with the wavelengths set to the F, d and
    C lines, exactly as in ``tests/refcases/cooke_triplet.json``. The glass indices at F, d and
    C are the refcase's (SK16 from the Hikari catalog, F2 from the Schott catalog as optiland
    reports them), interpolated in 1/λ² between those lines. Paraxial EFL 50.0216 mm, BFL
    42.4367 mm; the image plane is 0.229 mm inside the paraxial focus (the source's best focus).

    Args:
        clip: set semi-diameters (5 % over the largest real-ray height at the stated fields);
            ``False`` leaves every surface unclipped.

    Returns:
        The lens, with a 24 × 36 mm sensor (480 × 720 pixels of 50 µm).
    """
    sk16 = _fdc(1.6275674013357837, 1.6204088870389506, 1.6172754322856098, "SK16")
    f2 = _fdc(1.632081456782564, 1.6200401372462678, 1.6150316915761365, "F2")
    radii = (22.01359, -435.76044, -22.21328, 20.29192, 79.6836, -18.39533)
    # Largest real-ray height on each surface over the full pupil, all fields and wavelengths.
    sd = (8.557578525439208, 7.996519577804713, 3.997609359542727, 3.866233128491241,
          6.924877524754776, 7.287962911264125)
    surfaces = tuple(Sphere(1.0 / r, _sd(1.05 * h, clip)) for r, h in zip(radii, sd, strict=True))
    return Lens(
        surfaces=surfaces,
        thickness=jnp.array([3.25896, 6.00755, 0.99997, 4.75041, 2.95208, 42.20778]),
        materials=(sk16, Air(), f2, Air(), sk16, Air()),
        stop=3,
        epd=10.0,
        fields=jnp.array([0.0, 14.0, 20.0]),
        wavelengths=jnp.array(FDC),
        primary=1,
        sensor=Sensor(resolution=(480, 720), pixel_size=0.05),
        name="cooke_triplet",
    )


def double_gauss(*, clip: bool = True) -> Lens:
    """Double Gauss, f ≈ 100 mm, image-space F/5, fields 0/10/14°, two cemented doublets.

    Source: the double Gauss sample of optiland 0.6.3
    (``optiland/samples/objectives.py::DoubleGauss``; the same prescription as rayoptics'
    ``codev/tests/ag_dblgauss.seq``), exactly as in ``tests/refcases/double_gauss.json``:
    11 surfaces (8 spherical, 2 flat cemented faces and a flat stop between the doublets),
    glasses N-SSK2, N-SK2, F5 and N-SK16 given by their F, d and C indices. EPD 20.000744 mm
    makes the paraxial F-number exactly 5. Paraxial EFL 100.0037 mm.

    Args:
        clip: set semi-diameters (5 % over the largest real-ray height at the stated fields);
            ``False`` leaves every surface unclipped.

    Returns:
        The lens, with a 30 × 40 mm sensor (600 × 800 pixels of 50 µm).
    """
    nssk2 = _fdc(1.630451679115254, 1.622293795924426, 1.6187706069472942, "N-SSK2")
    nsk2 = _fdc(1.6148570659636294, 1.6073809696996346, 1.604135445245278, "N-SK2")
    f5 = _fdc(1.6146122610758453, 1.6034202574072252, 1.5987452734273884, "F5")
    nsk16 = _fdc(1.6275563487810216, 1.620409965080894, 1.6172716598778427, "N-SK16")
    inf = float("inf")
    radii = (56.20238, 152.2858, 37.68262, inf, 24.2313, inf, -28.37731, inf, -37.92546,
             177.41176, -79.41143)
    sd = (23.190895752200863, 21.481651316475787, 19.495827150018, 15.9202484797357,
          12.287834524640852, 6.588806766560191, 10.801921713215993, 13.065031296385893,
          15.900481047795234, 17.49003458030008, 18.10762766323471)
    surfaces = []
    for i, (r, h) in enumerate(zip(radii, sd, strict=True)):
        h = _sd(1.05 * h, clip)
        if i == 5:
            surfaces.append(Stop(h))
        elif r == inf:
            surfaces.append(Plane(h))
        else:
            surfaces.append(Sphere(1.0 / r, h))
    return Lens(
        surfaces=tuple(surfaces),
        thickness=jnp.array([8.75, 0.5, 12.5, 3.8, 16.369445, 13.747957, 3.8, 11.0, 0.5, 7.0,
                             61.487536]),
        materials=(nssk2, Air(), nsk2, f5, Air(), Air(), f5, nsk16, Air(), nsk16, Air()),
        stop=5,
        epd=20.000744101602084,
        fields=jnp.array([0.0, 10.0, 14.0]),
        wavelengths=jnp.array(FDC),
        primary=1,
        sensor=Sensor(resolution=(600, 800), pixel_size=0.05),
        name="double_gauss",
    )


# Plastics of the cellphone lens, by (nd, Vd) as the source's material table lists them.
def _plastic(name: str) -> AbstractMaterial:
    nd_vd = {
        "COC": (1.5337, 56.22),
        "POLYSTYR": (1.5904, 30.87),
        "OKP4": (1.6328, 23.34),
        "POLYCARB": (1.5855, 29.91),
    }[name]
    return ModelGlass(nd_vd[0], nd_vd[1], name=name)


# (c [1/mm], k, [A2, A4, ..., A12], semi-diameter [mm], thickness to next [mm], medium after).
_CELLPHONE6 = (
    (0.038202159106731415, 44.63999938964844,
     (0.10169609636068344, -0.00867919996380806, -0.004602653905749321,
      -0.0007934388122521341, -0.0001031243009492755, -1.1826809895865154e-05),
     1.2615166187286377, 0.8701000120490789, "COC"),
    (-0.041344691067934036, 107.41000366210938,
     (-0.07621642202138901, -0.002731784014031291, -0.0019592440221458673,
      -0.0002947986067738384, -2.5342629669466987e-05, -9.511782081972342e-07),
     1.4630464792251587, 0.13559997081756592, "air"),
    (-0.048397138714790344, 84.05000305175781,
     (-0.0843675285577774, 0.002311917021870613, 0.0025668758898973465,
      0.00035044251126237214, 2.8156569896964356e-05, 8.283241754725168e-07),
     1.5295305728912354, 0.4294999837875366, "POLYSTYR"),
    (0.023843349888920784, 117.80999755859375,
     (0.06003988906741142, -0.005461866036057472, -0.0020211089868098497,
      -0.0003140408080071211, -3.489114169497043e-05, -3.081800059590023e-06),
     1.743809747695923, 0.19910001754760742, "air"),
    (0.027934540063142776, 26.3799991607666,
     (0.029759999364614487, 0.0015477819833904505, -0.0006269668811000884,
      -0.00013235019287094474, -2.3526090444647707e-05, -3.6659139368566684e-06),
     1.8279924869537354, 0.7339999675750732, "COC"),
    (-0.020613230764865875, 147.14999389648438,
     (-0.04874534159898758, -0.005590604152530432, 0.0005042834091000259,
      0.00011991679639322683, 1.709496973489877e-05, 2.0926399884046987e-06),
     1.9221556663513184, 0.28480005264282227, "air"),
    (-0.012926749885082245, -5.5,
     (0.021369129419326782, -0.0011603289749473333, -0.0004946204135194421,
      -0.00010521370131755248, -1.550301931274589e-05, -1.668641971264151e-06),
     2.0543778419494627, 0.8080999851226807, "POLYSTYR"),
    (-0.02391391061246395, -23.6299991607666,
     (-0.08072532713413239, 0.003623096039518714, 0.0006184949888847768,
      5.498925020219758e-05, 4.507945959630888e-06, 1.7983199995796895e-07),
     2.2287571907043455, 0.6427001953125, "air"),
    (0.01589656062424183, -224.30999755859375,
     (0.06332910060882568, -0.010128890164196491, -0.0008300942718051374,
      -7.00999498803867e-06, 4.555577106657438e-06, 5.626757229038049e-07),
     2.667209434509277, 0.5965995788574219, "OKP4"),
    (-0.00529241980984807, 9.949999809265137,
     (0.002614967990666628, 0.00015060040459502488, -0.00041015620809048414,
      -7.3098526627291e-05, -4.518207788350992e-06, 4.48194299451643e-07),
     2.8222156047821043, 0.601600170135498, "air"),
    (-0.05408567935228348, -145.80999755859375,
     (-0.11755599826574326, 0.00215062010101974, 0.00036096569965593517,
      1.2568560123327188e-05, -2.3219720333145233e-06, -6.583694016626396e-07),
     2.8567808151245115, 0.40000009536743164, "POLYCARB"),
    (0.016189759597182274, -201.27000427246094,
     (0.0709935873746872, -0.007450900971889496, -8.592064841650426e-05,
      2.4292710804729722e-05, 1.8757780253508827e-06, -2.457003063227603e-07),
     3.4938486099243162, 1.2270000000000003, "air"),
)


def cellphone6(*, clip: bool = True) -> Lens:
    """A 6-element plastic aspheric cellphone lens: stop first, 80° FoV, about F/2, f ≈ 5 mm.

    Source: the 80° cellphone lens designed with DeepLens by Yang, Fu and Heidrich
    ("Curriculum learning for ab initio deep learned refractive optics", Nat. Commun. 15,
    6572 (2024)), published as ``lenses/cellphone/cellphone80deg.json`` in the DeepLens
    repository (github.com/singer-yang/DeepLens). Twelve even aspheres to A12 (the series
    starts at A2 r², Zemax EVENASPH PARM1; much of each surface's power sits in A2, and the
    conics are large, −224 … 147), after a 2.18 mm stop 0.01 mm in front of the first surface.
    Materials COC, polystyrene, OKP4 and polycarbonate are model glasses from (nd, Vd) as the
    source's material table lists them. Total track 6.939 mm, square sensor of side
    5.416 mm (7.66 mm diagonal). First-order data (A2 included): paraxial EFL 5.105 mm,
    F/2.34; the source's metadata quotes f = 4.35 mm and F/2.0, an edge-of-field figure
    (the real chief ray at 40° lands at 3.70 mm, 13 % barrel distortion against f·tanθ).
    The source's surface radii ("r") are its clear apertures and are used as
    semi-diameters.

    Args:
        clip: use the source's clear apertures as semi-diameters; ``False`` leaves every
            surface unclipped.

    Returns:
        The lens, with fields 0/10/20/30/40° and a 1024 × 1024 sensor of 5.416 mm.
    """
    surfaces = [Stop(_sd(1.09, clip))]
    thickness = [0.009999999776482582]
    materials: list[AbstractMaterial] = [Air()]
    for c, k, a, h, t, mat in _CELLPHONE6:
        surfaces.append(EvenAsphere(c=c, k=k, coeffs=jnp.array(a), semi_diameter=_sd(h, clip)))
        thickness.append(t)
        materials.append(Air() if mat == "air" else _plastic(mat))
    side = 5.416437943888954
    return Lens(
        surfaces=tuple(surfaces),
        thickness=jnp.array(thickness),
        materials=tuple(materials),
        stop=0,
        epd=2.18,
        fields=jnp.array([0.0, 10.0, 20.0, 30.0, 40.0]),
        wavelengths=jnp.array(FDC),
        primary=1,
        sensor=Sensor(resolution=(1024, 1024), pixel_size=side / 1024),
        name="cellphone6",
    )


ZOO = {"cooke_triplet": cooke_triplet, "double_gauss": double_gauss, "cellphone6": cellphone6}
"""Name → constructor for every sample lens."""
