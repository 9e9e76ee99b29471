"""The nonlinear Bo-105-class truth model: 6-DoF rigid body, MBC flapping, inflow, actuators.

State vector (SI), in :attr:`Bo105Model.state_names` order:

* rigid body ``u v w`` (m/s), ``p q r`` (rad/s), ``phi theta psi`` (rad);
* rotor ``beta0 beta1c beta1s`` (rad) and their time derivatives ``beta0_dot …`` (rad/s);
* inflow ``lambda0`` (baseline) or ``lambda0 lambda1s lambda1c`` (Pitt–Peters), then the tail
  rotor inflow ``lambda0T`` (non-dimensional);
* actuators ``theta0 theta1s theta1c theta0T``: blade angles in rad, first-order lags of the
  stick-commanded angles (:class:`~.parameters.StickMixing`).

Controls are stick positions in % of travel, ``[long, lat, coll, ped]``. An optional gust
``[u_g v_g w_g p_g q_g r_g]`` (m/s, rad/s, body axes; :mod:`.turbulence`) moves the air: rotor,
fuselage, tail rotor and surfaces see the body velocity and rates minus the gust, the rigid
body and the flapping blades' inertia the true ones. See docs/truth-model.md.
"""

from __future__ import annotations

import numpy as np
from rotorid.errors import DataError

from . import airframe, inflow, rotor
from .parameters import Bo105Config

RIGID_BODY = ("u", "v", "w", "p", "q", "r", "phi", "theta", "psi")
ROTOR = ("beta0", "beta1c", "beta1s", "beta0_dot", "beta1c_dot", "beta1s_dot")
ACTUATORS = ("theta0", "theta1s", "theta1c", "theta0T")
#: Measurement channels returned by :meth:`Bo105Model.measurements`.
MEASUREMENTS = ("ax", "az", "q", "theta", "ay", "p", "phi", "r")


class Bo105Model:
    """Nonlinear Bo-105-class helicopter, vectorised over a batch of states.

    Construct with ``Bo105Model(config)``; the model holds no mutable state.
    """

    def __init__(self, config: Bo105Config = Bo105Config()):
        self.config = config
        inflow_states = (("lambda0",) if config.inflow == "baseline"
                         else ("lambda0", "lambda1s", "lambda1c"))
        self.state_names: tuple[str, ...] = (RIGID_BODY + ROTOR + inflow_states + ("lambda0T",)
                                             + ACTUATORS)
        self.n_states: int = len(self.state_names)
        self.index = {name: i for i, name in enumerate(self.state_names)}
        self._inflow_slice = slice(len(RIGID_BODY) + len(ROTOR),
                                   len(RIGID_BODY) + len(ROTOR) + len(inflow_states))
        c = config
        gs, gc = np.sin(c.shaft_tilt), np.cos(c.shaft_tilt)
        #: body → hub rotation (rows: hub x, y, z axes in body axes; hub z down the shaft)
        self._hub = np.array([[gc, 0.0, gs], [0.0, 1.0, 0.0], [-gs, 0.0, gc]])
        self._disc = c.air_density * np.pi * c.radius**2 * c.tip_speed**2  # N per C_F
        inertia = np.array([[c.ixx, 0.0, -c.ixz], [0.0, c.iyy, 0.0], [-c.ixz, 0.0, c.izz]])
        self._inertia = inertia
        self._inertia_inv = np.linalg.inv(inertia)
        self._mixing = c.mixing.matrix
        self._mixing_centre = np.asarray(c.mixing.centre)

    # ------------------------------------------------------------------ public interface
    def derivatives(self, x: np.ndarray, stick: np.ndarray,
                    gust: np.ndarray | None = None) -> np.ndarray:
        """dx/dt, shape (B, n_states), for states x (B, n_states) SI, stick (B, 4) in % and
        an optional gust (B, 6) (module docstring; None is still air)."""
        x, stick = self._check(x, stick)
        return self._evaluate(x, stick, gust)[0]

    def measurements(self, x: np.ndarray, stick: np.ndarray,
                     gust: np.ndarray | None = None) -> np.ndarray:
        """(B, 8) ``[ax, az, q, theta, ay, p, phi, r]``: specific force at the CG in body axes
        (m/s², total, ≈ −g on az in hover), rates (rad/s), attitudes (rad); ``gust`` as for
        :meth:`derivatives`."""
        x, stick = self._check(x, stick)
        specific = self._evaluate(x, stick, gust)[1]["specific_force"]
        i = self.index
        return np.stack([specific[:, 0], specific[:, 2], x[:, i["q"]], x[:, i["theta"]],
                         specific[:, 1], x[:, i["p"]], x[:, i["phi"]], x[:, i["r"]]], axis=1)

    def loads(self, x: np.ndarray, stick: np.ndarray) -> dict:
        """Diagnostics for states x (B, n_states): specific force (B, 3) m/s², main-rotor
        thrust (B,) N, main- and tail-rotor shaft power (B,) W, and the engine power (B,) W
        (their sum over :attr:`Bo105Config.drive_efficiency`)."""
        x, stick = self._check(x, stick)
        return self._evaluate(x, stick)[1]

    # ------------------------------------------------------------------ internals
    def _check(self, x, stick):
        x = np.asarray(x, dtype=float)
        stick = np.asarray(stick, dtype=float)
        if x.ndim != 2 or x.shape[1] != self.n_states:
            raise DataError(f"Bo105Model: states must have shape (B, {self.n_states}) "
                            f"({', '.join(self.state_names)}), got {x.shape}")
        if stick.shape != (x.shape[0], 4):
            raise DataError(f"Bo105Model: stick must have shape ({x.shape[0]}, 4) "
                            f"[long, lat, coll, ped] in %, got {stick.shape}")
        return x, stick

    def _evaluate(self, x, stick, gust=None):
        c = self.config
        hub = self._hub
        omega_r = c.omega
        vel, rates = x[:, 0:3], x[:, 3:6]
        # air-relative motion for the aerodynamics (the same arrays in still air)
        air_vel, air_rates = (vel, rates) if gust is None else (vel - gust[:, :3],
                                                                 rates - gust[:, 3:])
        phi, theta = x[:, 6], x[:, 7]
        flap, flap_dot = x[:, 9:12], x[:, 12:15]
        lam = x[:, self._inflow_slice]
        lambda0t = x[:, self.index["lambda0T"]]
        blades = x[:, -4:]

        # --- main rotor
        hub_vel = airframe.point_velocity(air_vel, air_rates, c.hub_position)
        mu = hub_vel @ hub.T / c.tip_speed
        hub_rates = rates @ hub.T / omega_r
        air_hub_rates = air_rates @ hub.T / omega_r
        if c.inflow == "baseline":
            lam3 = np.empty_like(flap)
            lam3[:, 0] = lam[:, 0]
            lam3[:, 1], lam3[:, 2] = inflow.baseline_harmonics(lam[:, 0], mu)
        else:
            lam3 = lam
        loads = rotor.rotor_loads(
            mu, air_hub_rates, flap, flap_dot / omega_r, lam3, blades[:, :3],
            solidity=c.solidity, lift_slope=c.lift_slope, twist=c.twist,
            lock_number=c.lock_number, profile_drag=c.profile_drag)
        spring = 0.5 * c.n_blades * c.flap_spring
        torque = loads.torque * self._disc * c.radius
        hub_moment = np.empty_like(flap)
        hub_moment[:, 0] = -spring * flap[:, 2]
        hub_moment[:, 1] = -spring * flap[:, 1]
        hub_moment[:, 2] = torque
        mr_force = (loads.force * self._disc) @ hub
        mr_moment = hub_moment @ hub + airframe.moment_about_cg(mr_force, c.hub_position)

        # --- tail rotor, fuselage, empennage
        tr_force, tr_moment, lambda0t_rate, tr_power = airframe.tail_rotor(
            air_vel, air_rates, blades[:, 3], lambda0t, c)
        fus_force, fus_moment = airframe.fuselage_loads(air_vel, c)
        tp_force, tp_moment = airframe.tailplane_loads(air_vel, air_rates, c)
        fin_force, fin_moment = airframe.fin_loads(air_vel, air_rates, c)
        force = mr_force + tr_force + fus_force + tp_force + fin_force
        moment = mr_moment + tr_moment + fus_moment + tp_moment + fin_moment

        # --- rigid body (reference §2.1), written into dx in state order
        n = self.index
        dx = np.empty_like(x)
        p, q, r = rates.T
        sphi, cphi = np.sin(phi), np.cos(phi)
        sth, cth = np.sin(theta), np.cos(theta)
        g = c.gravity
        specific = force / c.mass
        accel = specific - airframe.cross(rates, vel)
        accel[:, 0] -= g * sth
        accel[:, 1] += g * cth * sphi
        accel[:, 2] += g * cth * cphi
        dx[:, 0:3] = accel
        gyro = airframe.cross(rates, rates @ self._inertia.T)
        rate_dot = (moment - gyro) @ self._inertia_inv.T
        dx[:, 3:6] = rate_dot
        turn = (q * sphi + r * cphi) / cth
        dx[:, n["phi"]] = p + turn * sth
        dx[:, n["theta"]] = q * cphi - r * sphi
        dx[:, n["psi"]] = turn

        # --- flap dynamics (body accelerations first: with e = 0 they do not depend on β̈)
        dx[:, 9:12] = flap_dot
        dx[:, 12:15] = rotor.flap_accelerations(
            flap, flap_dot / omega_r, loads.flap_forcing, hub_rates,
            rate_dot @ hub.T / omega_r**2, c.flap_frequency_squared) * omega_r**2

        # --- inflow
        if c.inflow == "baseline":
            dx[:, self._inflow_slice] = omega_r * inflow.uniform_inflow_rate(
                lam[:, 0], mu, loads.thrust)[:, None]
        else:
            forcing = np.stack([loads.thrust, loads.roll_moment, loads.pitch_moment], axis=1)
            dx[:, self._inflow_slice] = omega_r * inflow.pitt_peters_rate(lam, mu, forcing)
        dx[:, n["lambda0T"]] = lambda0t_rate

        # --- actuators
        command = self._mixing_centre + stick @ self._mixing.T
        dx[:, -4:] = (command - blades) / c.actuator_time_constant

        rotor_power = torque * omega_r
        info = {"specific_force": specific, "thrust": loads.thrust * self._disc,
                "rotor_power": rotor_power, "tail_power": tr_power,
                "power": (rotor_power + tr_power) / c.drive_efficiency}
        return dx, info
