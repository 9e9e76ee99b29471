"""Bo-105-class configuration data of the truth model, SI units, with sources.

Sources (facts only; see /work/shared/reference/truth-model.md §3 and docs/truth-model.md):

* **Padfield**: G. D. Padfield, *Helicopter Flight Dynamics*, 2nd ed. (2007), Table 4B.1 —
  mass, inertias, rotor geometry, flap spring, tail-rotor and empennage data.
* **HEROES**: the Padfield Bo-105 data as transcribed in the HEROES toolbox (blade profile-drag
  polynomial, fuselage polynomials, tailplane and fin lift data).
* **Reference §2.0**: positions relative to the CG, fin sign, tailplane downwash K = 0 and the
  fuselage-moment calibration factors (0.3 pitch, 0.4 yaw) that reproduce Padfield's Helisim
  derivatives. These factors are a calibration, not a source.
* **Assumed**: actuator time constant, stick mixing ranges, power limit (engineering choices,
  documented in docs/truth-model.md).

Axes: body axes at the CG, x forward, y right, z down. Angles in rad, blade angles in rad.
"""

from __future__ import annotations

import math

import attrs
import numpy as np
from rotorid.errors import StructureError

#: Names of the four blade angles, in the order of every blade-angle array.
BLADE_ANGLES = ("theta0", "theta1s", "theta1c", "theta0T")
#: Names of the four stick channels (% of travel), in the order of every stick array.
STICKS = ("long", "lat", "coll", "ped")
#: Blade angle driven by each stick channel.
STICK_TO_BLADE = {"long": "theta1s", "lat": "theta1c", "coll": "theta0", "ped": "theta0T"}

_DEG = math.pi / 180.0


def _positive(instance, attribute, value):
    if not (np.all(np.isfinite(value)) and np.all(np.asarray(value) > 0)):
        raise StructureError(f"Bo105Config.{attribute.name} must be finite and positive, "
                             f"got {value!r}")


def _vector3(value):
    array = tuple(float(v) for v in value)
    if len(array) != 3:
        raise StructureError(f"a position must have 3 components (x, y, z in m), got {value!r}")
    return array


@attrs.frozen
class StickMixing:
    """Trim-independent linear map from stick (% of travel, 0 = centre) to blade angles (rad).

    ``blade[i] = centre[i] + gain[i] * stick[j]`` with the stick channel ``j`` that drives blade
    angle ``i`` (:data:`STICK_TO_BLADE`). Signs: long > 0 is stick forward (nose down, so θ1s
    decreases); lat > 0 is stick right (right roll, θ1c decreases); coll > 0 is up (θ0
    increases); ped > 0 is right pedal (nose right, θ0T decreases).

    Attributes:
        centre: blade angles at centred sticks, rad, order (θ0, θ1s, θ1c, θ0T).
        gain: rad per % of travel, same order.
    """

    centre: tuple = attrs.field(
        default=(12.0 * _DEG, 0.0, 0.0, 6.0 * _DEG),
        converter=lambda v: tuple(float(x) for x in v))
    gain: tuple = attrs.field(
        default=(0.12 * _DEG, -0.12 * _DEG, -0.08 * _DEG, -0.14 * _DEG),
        converter=lambda v: tuple(float(x) for x in v))

    def __attrs_post_init__(self):
        if len(self.centre) != 4 or len(self.gain) != 4 or not all(self.gain):
            raise StructureError("StickMixing needs 4 centres and 4 non-zero gains "
                                 "(θ0, θ1s, θ1c, θ0T), rad and rad per %")

    @property
    def matrix(self) -> np.ndarray:
        """(4, 4) rad per %: blade angles (θ0, θ1s, θ1c, θ0T) per stick (long, lat, coll, ped)."""
        m = np.zeros((4, 4))
        for j, stick in enumerate(STICKS):
            i = BLADE_ANGLES.index(STICK_TO_BLADE[stick])
            m[i, j] = self.gain[i]
        return m

    def blade_angles(self, stick) -> np.ndarray:
        """Blade angles in rad, shape (..., 4), from stick positions in %, shape (..., 4)."""
        return np.asarray(self.centre) + np.asarray(stick, dtype=float) @ self.matrix.T

    def stick(self, blade_angles) -> np.ndarray:
        """Stick positions in %, shape (..., 4), from blade angles in rad, shape (..., 4)."""
        delta = np.asarray(blade_angles, dtype=float) - np.asarray(self.centre)
        return delta @ np.linalg.inv(self.matrix).T


@attrs.frozen
class Bo105Config:
    """Bo-105 configuration (SI). Defaults are Padfield's Helisim data unless noted.

    Inflow model: ``"baseline"`` (dynamic uniform λ0 with the quasi-steady Coleman fore-aft
    gradient, reference §1) or ``"pitt-peters"`` (three-state Pitt–Peters, reference §2.3).
    """

    # --- airframe (Padfield Table 4B.1)
    mass: float = attrs.field(default=2200.0, validator=_positive)  #: kg
    ixx: float = attrs.field(default=1433.0, validator=_positive)  #: kg m²
    iyy: float = attrs.field(default=4973.0, validator=_positive)  #: kg m²
    izz: float = attrs.field(default=4099.0, validator=_positive)  #: kg m²
    ixz: float = 660.0  #: kg m², product of inertia
    # --- main rotor (Padfield Table 4B.1; profile drag from HEROES)
    radius: float = attrs.field(default=4.91, validator=_positive)  #: m
    n_blades: int = 4
    chord: float = attrs.field(default=0.27, validator=_positive)  #: m
    omega: float = attrs.field(default=44.4, validator=_positive)  #: rad/s, held constant
    lift_slope: float = attrs.field(default=6.113, validator=_positive)  #: 1/rad
    twist: float = -0.14  #: rad, linear, θ0 referenced at the rotor centre
    shaft_tilt: float = 3.0 * _DEG  #: rad, shaft tilted forward
    flap_inertia: float = attrs.field(default=231.7, validator=_positive)  #: kg m²
    flap_spring: float = attrs.field(default=113330.0, validator=_positive)  #: N m/rad (CSER)
    #: section c_d = d0 + d1·α + d2·α² (HEROES), at the local blade incidence α.
    profile_drag: tuple = (0.0074, 0.00961, 0.29395)
    hub_position: tuple = attrs.field(default=(-0.080, 0.0, -1.48), converter=_vector3)  #: m
    # --- tail rotor (Padfield; CR-3144 for Ω_T; position from reference §2.0)
    tail_radius: float = attrs.field(default=0.95, validator=_positive)  #: m
    tail_blades: int = 2
    tail_chord: float = attrs.field(default=0.18, validator=_positive)  #: m
    tail_lift_slope: float = attrs.field(default=5.7, validator=_positive)  #: 1/rad
    tail_omega: float = attrs.field(default=232.7, validator=_positive)  #: rad/s
    tail_position: tuple = attrs.field(default=(-6.08, 0.0, -1.72), converter=_vector3)  #: m
    # --- fuselage polynomials (Padfield via HEROES), N or N m at the reference speed,
    #     coefficients of 1, α, α², α³ (or β), α and β in rad
    fuselage_x: tuple = (-580.6, -454.0, 6.2, 4648.9)
    fuselage_z: tuple = (-51.1, -1202.0, 1515.7, -604.2)
    fuselage_m: tuple = (-1191.8, 12752.0, 8201.3, -5796.7)
    fuselage_y: tuple = (-6.9, -2399.0, -1.7, 12.7)
    fuselage_n: tuple = (0.0, -10028.0, 0.0, 0.0)
    fuselage_reference_speed: float = 30.48  #: m/s, speed of the polynomial fits
    fuselage_pitch_scale: float = 0.3  #: calibration (reference §2.0), not a source
    fuselage_yaw_scale: float = 0.4  #: calibration (reference §2.0), not a source
    #: the fits are valid for |α|, |β| ≲ 20°; angles are smoothly saturated at this value
    fuselage_angle_limit: float = attrs.field(default=20.0 * _DEG, validator=_positive)
    # --- tailplane (two halves) and fin (HEROES Padfield data; positions reference §2.0)
    tailplane_area: float = 0.803  #: m², both halves
    tailplane_lift_slope: float = 3.262  #: 1/rad
    tailplane_incidence: float = 0.0698  #: rad
    tailplane_position: tuple = attrs.field(default=(-4.64, 0.97, 0.0), converter=_vector3)
    fin_area: float = 0.805  #: m²
    fin_lift_slope: float = 2.704  #: 1/rad
    fin_incidence: float = 0.0812  #: rad
    fin_position: tuple = attrs.field(default=(-5.50, 0.0, -0.86), converter=_vector3)
    surface_lift_limit: float = 2.0  #: |C_L| cap of tailplane and fin (HEROES)
    # --- environment
    air_density: float = attrs.field(default=1.225, validator=_positive)  #: kg/m³, ISA SL
    gravity: float = 9.80665  #: m/s²
    # --- modelling options (assumed values, documented)
    inflow: str = attrs.field(default="baseline")
    actuator_time_constant: float = attrs.field(default=0.03, validator=_positive)  #: s
    mixing: StickMixing = attrs.field(factory=StickMixing)
    power_limit_kw: float = attrs.field(default=626.0, validator=_positive)  #: 2 × 313 kW
    #: engine power = rotor power / efficiency (gearboxes, tail drive, accessories; assumed)
    drive_efficiency: float = attrs.field(default=0.95, validator=_positive)

    @inflow.validator
    def _check_inflow(self, attribute, value):
        if value not in ("baseline", "pitt-peters"):
            raise StructureError(f"Bo105Config.inflow must be 'baseline' or 'pitt-peters', "
                                 f"got {value!r}")

    # --- derived quantities
    @property
    def solidity(self) -> float:
        """Main-rotor solidity σ = N_b c / (π R)."""
        return self.n_blades * self.chord / (math.pi * self.radius)

    @property
    def tip_speed(self) -> float:
        """Main-rotor tip speed ΩR, m/s."""
        return self.omega * self.radius

    @property
    def lock_number(self) -> float:
        """γ = ρ a0 c R⁴ / I_β."""
        return self.air_density * self.lift_slope * self.chord * self.radius**4 / self.flap_inertia

    @property
    def flap_frequency_squared(self) -> float:
        """λβ² = 1 + K_β / (I_β Ω²)."""
        return 1.0 + self.flap_spring / (self.flap_inertia * self.omega**2)

    @property
    def tail_solidity(self) -> float:
        """Tail-rotor solidity."""
        return self.tail_blades * self.tail_chord / (math.pi * self.tail_radius)
