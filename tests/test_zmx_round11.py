"""What the eleventh round's survey of the reader's refusals (corpora 5-10 and tests/data,
/work/notes/s53/zmx11_refusals.txt) showed.

The refusals that real files hit are of information the file lacks or of systems a jaxlens
``Lens`` cannot hold, so they stay refusals; what changed is that each now says why, naming
the line, instead of "not supported":

* An object-space telecentric system (FTYP's second value 1; the shipped lithography lens
  US05831776): OpticStudio launches every chief ray parallel to the axis (the entrance pupil
  at infinity), a ``Lens`` holds its fields as chief-ray angles toward a pupil at a finite
  distance.
* ``FLOA`` with no semi-diameter on the stop (DeepLens's writer leaves its aperture stop
  without a DIAM line): the pupil's size is not in the file; the message names the stop
  surface and its line.
* A tilted object plane at a finite distance (Kraken's Scheimpflug sample, a ``TILTSURF``
  object): the off-axis object points lie off the vertex plane, where a ``Lens`` puts them.

Each snippet is hand-written after the line that showed the class; each refusal is paired
with a control that the same snippet without the feature loads.
"""

import pytest

from jaxlens.io import zmx_read


def _lens(*, ftyp="0 0", aperture="ENPD 10", stop_diam="DIAM 5 1 0 0 1", obj_disz="100",
          obj_surface="TYPE STANDARD\n  CURV 0.0"):
    """A BK7 singlet after the corpus files' lines: surface 1 is the stop (its DIAM line is
    ``stop_diam``), the object at ``obj_disz``, two fields on YFLN."""
    return f"""VERS 190513 80 123457 L123457
MODE SEQ
UNIT MM X W X CM MR CPMM
{aperture}
GCAT SCHOTT
FTYP {ftyp} 2 1 0 0 0
XFLN 0 0
YFLN 0 2
WAVM 1 0.5875618 1
PWAV 1
SURF 0
  {obj_surface}
  DISZ {obj_disz}
SURF 1
  STOP
  TYPE STANDARD
  CURV 0.02
  DISZ 5
  GLAS N-BK7
  {stop_diam}
SURF 2
  TYPE STANDARD
  CURV -0.02
  DISZ 60
  DIAM 6 1 0 0 1
SURF 3
  TYPE STANDARD
  CURV 0
  DISZ 0
"""


def test_object_space_telecentric_header_loads():
    """US05831776's header (round 38a: refused before): an object-space telecentric lens
    (Lens.object_na), its fields object heights, its aperture the object-space NA."""
    lens = zmx_read.loads(_lens(ftyp="1 1", aperture="OBNA 1.5E-1 0"))
    assert lens.telecentric_object and float(lens.object_na) == 0.15


def test_object_heights_without_the_telecentric_flag_load():
    """The control: the same header with the flag 0 reads (object heights, OBNA)."""
    lens = zmx_read.loads(_lens(ftyp="1 0", aperture="OBNA 1.5E-1 0"))
    assert lens.fields.shape == (2,) and float(lens.epd) > 0


def test_floa_without_a_stop_size_names_the_stop_and_says_the_size_is_missing():
    """DeepLens's writer: FLOA, and the STOP surface with no DIAM line. The message names
    the stop surface and its line (the FLOA line alone pointed away from what is missing)."""
    with pytest.raises(ValueError, match=r"<zmx>:4: FLOA needs .*\(surface 1, line 15\).*"
                                         r"pupil's size is not in the file"):
        zmx_read.loads(_lens(aperture="FLOA", stop_diam=""))


def test_floa_with_a_stop_size_loads():
    """The control: FLOA with the stop's DIAM 5 gives the pupil of a stop on surface 1,
    EPD = 2 x 5 mm."""
    lens = zmx_read.loads(_lens(aperture="FLOA"))
    assert float(lens.epd) == pytest.approx(10.0, rel=1e-12)


def test_tilted_object_plane_refusal_says_why():
    """Kraken's Scheimpflug sample: a TILTSURF object with PARM 2 = -1 (45 degrees) at a
    finite distance. The message names the PARM line and says where the object points are."""
    tilted = "TYPE TILTSURF\n  CURV 0.0\n  PARM 1 0\n  PARM 2 -1"
    with pytest.raises(ValueError, match=r"<zmx>:15: the object surface .*PARM 2 -1.*off the "
                                         r"vertex plane.*wrong distance"):
        zmx_read.loads(_lens(obj_surface=tilted, obj_disz="50"))


def test_tilted_object_plane_at_infinity_loads():
    """The control: at infinity the object's shape is moot and the file reads."""
    tilted = "TYPE TILTSURF\n  CURV 0.0\n  PARM 1 0\n  PARM 2 -1"
    lens = zmx_read.loads(_lens(obj_surface=tilted, obj_disz="INFINITY"))
    assert lens.object_distance is None
