"""The keys a JSON lens file may hold, and the refusal of near misses and synonyms.

The reader ignores unknown keys, so that informational data (``paraxial``,
``semi_diameter_real_rays``, …) can live in the same file (``description`` is read, as
``Lens.description``). A misspelled known key
(``"wavelength_nm"``, ``"radus"``, ``"Thickness"``) or a synonym of one from another program
(``"glass"``, ``"R"``, ``"k"``, ``"stop"``) would then silently fall back to its default, so
such a key is refused instead, naming the key this format uses. Each table maps the keys of
one level of the file to their synonyms (lower case). The sections read whole (``units``,
``sensor``, ``object``, ``fields``: ``CLOSED``) take no informational keys: any other key
there is refused.
"""

from __future__ import annotations

import re
import warnings
from typing import Any

TOP = {
    "format": (), "name": (), "description": (), "surfaces": (), "units": (),
    "aperture": ("f_number", "fnum", "fno", "f/#"), "epd": (), "EPD": (),
    "fields": ("field_angles", "fields_deg", "field_angles_deg", "angles", "fov"),
    "wavelengths_um": ("lambda_um", "lambdas_um", "wavelengths_micron"),
    "wavelengths_nm": ("lambda_nm", "lambdas_nm"), "wavelengths": ("lambda", "lambdas"),
    "primary": ("primary_index", "primary_wavelength_index"), "primary_wavelength_um": (),
    "primary_wavelength_nm": (), "primary_wavelength": (),
    "stop_surface_index": ("stop", "stop_index", "stop_surface"),
    "object": ("object_distance", "object_dist", "obj_distance", "object_thickness"),
    "sensor": (), "afocal_image_space": ("afocal", "afocal_image", "afocal_mode"),
    "object_space_telecentric": ("telecentric", "telecentric_object", "object_telecentric",
                                 "telecentric_object_space"),
    "ray_aiming": ("aim", "aiming", "raim", "ray_aim"),
    "negative_propagation": ("go_back", "negative_distance", "negative_propagation_distance",
                             "backward_propagation"),
}
SURFACE = {
    "type": ("surface_type",), "curvature": ("c", "cv", "curv", "curvature_y"),
    "radius": ("r", "roc", "radius_of_curvature", "rad", "radius_y"),
    "thickness": ("t", "thick", "thi", "disz", "distance", "gap"),
    "conic": ("k", "cc", "conic_constant", "kappa", "conic_y"),
    "curvature_x": ("cx", "curv_x"), "radius_x": ("rx",), "conic_x": ("kx",),
    "zernike_coeffs": ("zernike_coefficients", "zernikes", "zernike_terms"),
    "zernike_decenter_x": (), "zernike_decenter_y": (), "extrapolate": (),
    "even_asphere_coeffs": ("asphere_coeffs", "aspheric_coeffs", "asphere_coefficients",
                            "aspheric_coefficients", "coeffs", "coefficients", "even_coeffs"),
    "odd_asphere_coeffs": ("odd_coeffs", "radial_coeffs"), "odd_x": (), "odd_y": (),
    "q_coeffs": ("qbfs_coeffs", "qcon_coeffs", "q_coefficients", "forbes_coeffs"),
    "norm_radius": ("normalization_radius", "normalisation_radius", "rnorm", "r_norm",
                    "norm_radius_mm"),
    "semi_diameter": ("diameter", "diam", "aperture_radius", "sd", "clear_aperture",
                      "clear_semi_diameter"),
    "is_stop": ("stop", "aperture_stop"), "material": ("glass", "glas", "medium"), "n": (),
    "index_at_wavelengths": ("indices_at_wavelengths", "n_at_wavelengths", "index_record"),
    "shape": (),
    # surface_json's kinds and per-surface data
    "y_coeffs": (), "focal_length": ("f", "efl", "focal"),
    "diffraction_order": (), "phase_coeffs": (), "lines_per_um": ("lpmm", "lines_per_mm"),
    "polynomial_coeffs": ("xy_coeffs", "xy_polynomial_coeffs", "xpolynom_coeffs"),
    "tan_x": (), "tan_y": (), "decenter_x": (), "decenter_y": (), "tilt_x_deg": ("tilt_x",),
    "tilt_y_deg": ("tilt_y",), "tilt_z_deg": ("tilt_z",), "order": (), "mirror": ("reflect",),
    "obscuration": ("obsc",), "apertures": ("aperture",),
}
APERTURE = {"epd": ("entrance_pupil_diameter", "pupil_diameter", "diameter"), "EPD": (),
            "fnum": ("fno", "f/#"), "FNUM": (), "f_number": (),
            "stop_semi_diameter": ("stop_radius", "stop_semi_diam"),
            "object_na": ("na", "obna", "object_space_na", "numerical_aperture")}
SENSOR = {"resolution": ("pixels", "res", "size_px"), "pixel_size": ("pixel_pitch", "pitch")}
FIELDS = {"type": ("kind",), "values": ("vals", "angles", "angles_deg", "values_deg",
                                        "field_angles", "fields", "deg", "degrees"),
          "vignetting": ("vignetting_factors", "vig")}
# Lens.vignetting's columns, one list of one value per field each (a missing one is 0).
VIGNETTING = {"vdx": ("vdxn", "decenter_x"), "vdy": ("vdyn", "decenter_y"),
              "vcx": ("vcxn", "compression_x", "compress_x"),
              "vcy": ("vcyn", "compression_y", "compress_y"),
              "van_deg": ("van", "vann", "angle", "angle_deg")}
OBJECT = {"distance": ("dist", "d", "thickness", "object_distance", "z")}
# A material object: a misspelled "vd" would leave a model glass without dispersion.
MATERIAL = {"name": ("glass",), "class": ("type", "kind"), "nd": ("n_d",),
            "vd": ("v_d", "abbe", "abbe_number"), "n": (), "indices": ("index_table",),
            "wavelengths_um": ("wavelengths", "wavelength_um"), "wavelengths_nm": (),
            "catalog": ("catalogue",)}
REQUIRED = {"fields": "values", "object": "distance"}
"""Sections that are read only for one key: without it the section would be ignored."""

_FORM = {"aperture": '{"aperture": {"fnum": F}}',
         "fields": '{"fields": {"values": [deg, ...]}}',
         "object": '{"object": {"distance": mm}}'}


def edit_distance(a: str, b: str) -> int:
    """Levenshtein distance between two short strings."""
    row = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        prev, row[0] = row[0], i
        for j, cb in enumerate(b, 1):
            prev, row[j] = row[j], min(row[j] + 1, row[j - 1] + 1, prev + (ca != cb))
    return row[-1]


def _allowed_edits(known: str) -> int:
    # One- and two-letter keys ("n") match only in another case: "nd" or "vd" are
    # informational glass data, not typos of "n".
    return 0 if len(known) <= 2 else 1 if len(known) <= 6 else 2


def no_misspelled(d: Any, known: dict[str, tuple[str, ...]], where: str) -> None:
    """Raise ``ValueError`` for a key of the mapping ``d`` that is a near miss of a known key
    or one of its synonyms (case ignored), naming the key to use; other keys pass."""
    if not isinstance(d, dict):
        return
    # Synonyms match exactly: a deliberate list, where near misses of "r" or "sd" would
    # catch unrelated informational keys.
    synonym = {s: k for k, syn in known.items() for s in syn}
    for key in d:
        if not isinstance(key, str) or key in known:
            continue
        near = sorted((dist, k) for k in known
                      if (dist := edit_distance(k.lower(), key.lower())) <= _allowed_edits(k))
        right = synonym.get(key.lower(), near[0][1] if near else None)
        if right:
            form = f", as in {_FORM[right]}" if known is TOP and right in _FORM else ""
            raise ValueError(f"{where}: unknown key {key!r}; did you mean {right!r}{form}? (a "
                             f"key not read would be ignored and its default used)")


def _units(u: Any, source: str) -> None:
    """Lengths must be mm (a file in inches or cm would be read as mm); wavelength and
    angle units are given by the keys (``wavelengths_nm``) and are degrees."""
    ok = {"length": ("mm", "millimeter", "millimeters", "millimetre", "millimetres"),
          "wavelength": ("um", "µm", "micron", "microns", "micrometer", "nm"),
          "angle": ("deg", "degree", "degrees")}
    if isinstance(u, str):  # "mm" or "mm; wavelengths in nm; angles in degrees"
        u = {"length": (re.findall(r"[^\W\d_]+", u) or [""])[0]}
    if not isinstance(u, dict):
        raise ValueError(f"{source}: units must be \"mm\" or an object such as "
                         f"{{\"length\": \"mm\"}}, got {u!r}")
    for what, unit in u.items():
        if what in ok and (not isinstance(unit, str) or unit.strip().lower() not in ok[what]):
            raise ValueError(f"{source}: units.{what} {unit!r} is not supported: lens files "
                             f"hold lengths in mm, angles in deg and wavelengths in the unit "
                             f"of their key (µm, or nm for *_nm); convert the file")


def check_keys(d: dict, source: str) -> None:
    """A lens file's top level and system sections: near misses and synonyms of known keys
    (the surfaces are checked where they are read), sections without their one key, units."""
    no_misspelled(d, TOP, source)
    for section, known in (("aperture", APERTURE), ("sensor", SENSOR), ("fields", FIELDS),
                           ("object", OBJECT)):
        no_misspelled(d.get(section), known, f"{source}: {section}")
    closed(d, source)
    for section, key in REQUIRED.items():
        v = d.get(section)
        if (section == "object" and section in d and not isinstance(v, dict)) or (
                isinstance(v, dict) and key not in v):
            raise ValueError(f"{source}: {section} needs {key!r}, as in {_FORM[section]}, got "
                             f"{v!r}")
    if "units" in d:
        _units(d["units"], source)
        _wavelength_unit(d, source)
    _weights(d, source)


UNITS = {"length": (), "wavelength": (), "angle": ()}
"""The keys of a ``units`` object."""

CLOSED = {"units": UNITS, "sensor": SENSOR, "object": OBJECT,
          "fields": {**FIELDS, "weights": ()}}
"""Sections read whole: every key of theirs is read (``fields.weights`` warned about), so
another key is a unit, a size or a field setting this reader would ignore (``"units":
{"lengths": "in"}`` read inches as mm, ``"fields": {"unit": "rad"}`` radians as degrees)."""


def closed(d: dict, source: str) -> None:
    """Refuse a key of a section in ``CLOSED`` that the section does not hold (the top level,
    the surfaces and ``aperture`` take informational keys; these sections do not)."""
    for section, known in CLOSED.items():
        v = d.get(section)
        if not isinstance(v, dict):
            continue
        no_misspelled(v, known, f"{source}: {section}")
        other = [k for k in v if k not in known]
        if other:
            raise ValueError(f"{source}: {section}: unknown key {other[0]!r}; {section} holds "
                             f"only {', '.join(known)} (a key not read would be ignored and "
                             f"its default used)")


WEIGHTS = (("fields", "weights", "fields"), (None, "field_weights", "fields"),
           ("wavelengths", "weights", "wavelengths"), (None, "wavelength_weights", "wavelengths"))
"""Where a file may weigh its fields or wavelengths (as Zemax's FWGN and WAVM do): read by
no one, as a key far from every known key, though the figures would differ with them."""


def _weights(d: dict, source: str) -> None:
    """Warn about unequal field or wavelength weights, as the ``.zmx`` reader does: a
    ``Lens`` holds no weights, so its figures over several fields or wavelengths weigh each
    equally (before: the key passed as a comment)."""
    for section, key, what in WEIGHTS:
        holder = d if section is None else d.get(section)
        if not isinstance(holder, dict) or key not in holder:
            continue
        w = holder[key]
        if isinstance(w, list) and len({repr(x) for x in w}) < 2:
            continue
        name = key if section is None else f"{section}.{key}"
        warnings.warn(f"{source}: {name} {w!r} is not read: a jaxlens Lens holds no weights, "
                      f"so its figures over several {what} weigh each equally (Zemax's "
                      f"weighted figures differ)", stacklevel=6)


def _wavelength_unit(d: dict, source: str) -> None:
    """A declared wavelength unit must be the unit of the file's wavelength key (µm for
    ``wavelengths_um`` and ``wavelengths``, nm for ``wavelengths_nm``): the key decides how
    the numbers are read, so a disagreeing ``units.wavelength`` was ignored."""
    u = d["units"]
    key = next((k for k in ("wavelengths_um", "wavelengths_nm", "wavelengths") if k in d), None)
    if not isinstance(u, dict) or not isinstance(u.get("wavelength"), str) or key is None:
        return
    declared = "nm" if u["wavelength"].strip().lower() == "nm" else "µm"
    implied = "nm" if key.endswith("_nm") else "µm"
    if declared != implied:
        raise ValueError(f"{source}: units.wavelength is {u['wavelength']!r}, but the "
                         f"wavelengths are given as {key!r}, which is read in {implied}; "
                         f"make them agree (use wavelengths_{'nm' if declared == 'nm' else 'um'})")
