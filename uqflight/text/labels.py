"""How figures name outputs and parameters: a description with its unit, each unit said once."""
from __future__ import annotations

OUTPUT_LABELS = {
    "alpha_deg": "angle of attack α [deg]",
    "theta_deg": "pitch attitude θ [deg]",
    "h_ft": "altitude h [ft]",
    "q_degps": "pitch rate q [deg/s]",
    "vtas_kt": "true airspeed V_TAS [kt]",
}
# The BACM's uncertain coefficients (aircraft/bacm/bacm.xml): CLalpha multiplies alpha in rad, Cmq the
# pitch rate in rad made dimensionless by c/2V; the others are plain coefficients. A patch's scale
# (aero/uq/scale/NAME) is a factor.
PARAMETER_UNITS = {"aero/uq/CL0": "-", "aero/uq/CLalpha": "1/rad", "aero/uq/CD0": "-", "aero/uq/k1": "-",
                   "aero/uq/k2": "-", "aero/uq/Cm0": "-", "aero/uq/Cmq": "1/rad"}
# JSBSim's property names end in their unit: velocities/vt-fps, inertia/weight-lbs, ...
PROPERTY_SUFFIXES = {"ft": "ft", "deg": "deg", "rad": "rad", "lbs": "lbs", "kts": "kt", "fps": "ft/s",
                     "sqft": "ft²", "slug_ft2": "slug·ft²", "rad_sec": "rad/s", "deg_sec": "deg/s", "psf": "psf",
                     "mps": "m/s", "m": "m", "kg": "kg", "sec": "s", "hz": "Hz", "mt": "m", "meters": "m",
                     "norm": "-", "deg_sec2": "deg/s²", "rad_sec2": "rad/s²", "ft_sec": "ft/s", "ft_sec2": "ft/s²",
                     "fps2": "ft/s²", "lbf": "lbf", "lbsft": "lbf·ft", "kt": "kt", "degps": "deg/s"}
# JSBSim's load factors carry no suffix: they are in g
UNITLESS_PROPERTIES = {"accelerations/Nx": "g", "accelerations/Ny": "g", "accelerations/Nz": "g"}
ANGLE_PERIODS = {"deg": 360.0, "rad": 2 * 3.141592653589793}  # an angle's period in its unit


def label(name: str, units: str = "") -> str:
    """Axis label of an output: its description and unit, e.g. "pitch attitude θ [deg]"."""
    if name in OUTPUT_LABELS:
        return OUTPUT_LABELS[name]
    return f"{name} [{units}]" if units else name


def short_label(name: str) -> str:
    """A panel title: the label without its unit, e.g. "pitch attitude θ"."""
    return label(name).split(" [")[0]


def parameter_unit(prop: str) -> str:
    """The unit of a parameter's property: the BACM coefficients' known units, "-" for a patch's
    scale factor, the unit a JSBSim name ends in (`-ft`, `_deg`, `-lbs` ...), else "" (unknown)."""
    if prop in PARAMETER_UNITS:
        return PARAMETER_UNITS[prop]
    if prop.startswith("aero/uq/scale/"):
        return "-"
    return name_unit(prop)


def name_unit(name: str) -> str:
    """The unit a JSBSim property or output name ends in: the longest suffix after a - or _ of its last
    part that names one (`attitude/psi-deg` deg, `velocities/vc-kts` kt, `h_ft` ft), else "" (unknown)."""
    if name in UNITLESS_PROPERTIES:
        return UNITLESS_PROPERTIES[name]
    tail = name.rsplit("/", 1)[-1].lower()
    for k, char in enumerate(tail):
        if char in "-_" and tail[k + 1:] in PROPERTY_SUFFIXES:
            return PROPERTY_SUFFIXES[tail[k + 1:]]
    return ""


def parameter_label(name: str, prop: str) -> str:
    """A parameter's axis label with its unit when known, e.g. "CLalpha [1/rad]"."""
    unit = parameter_unit(prop)
    return f"{name} [{unit}]" if unit else name


def shown_time(time, i: int) -> float:
    """The recorded time `time[i]` as a reader asked for it: snapped to the recording grid t0 + k / rate
    (the rate read from the grid to 4 digits) when within 10 % of a step of it, so that 9.99996 s (JSBSim's
    clock adding 1/120 s steps) reads 10 s and 24.9999 s reads 25 s; a time off that grid keeps its
    digits. Full precision stays in the time arrays."""
    t = float(time[i])
    if len(time) < 2:
        return t
    t0, step = float(time[0]), (float(time[-1]) - float(time[0])) / (len(time) - 1)
    if not step > 0:
        return t
    rate = float(f"{1.0 / step:.4g}")
    snapped = round(round(t0, 6) + round((t - t0) * rate) / rate, 9)
    return snapped + 0.0 if abs(snapped - t) <= 0.1 * step else t  # + 0.0: no "-0"
