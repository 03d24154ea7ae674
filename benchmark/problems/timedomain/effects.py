"""Time-domain effects: each one class, acting on extended-model rows.

Sizes are in the units each class documents; ``realistic`` ranges are the defaults of the
YAMLs in ``conf/effect/``. ``form`` options vary how the plant realises an effect (exponent of
a saturation curve, hard or smooth inverter drop, a double cage or a three-section deep-bar
ladder...), so that a diagnosis tuned to one form is checked on others.
"""

from __future__ import annotations

import numpy as np

from benchmark.core.effects import Effect
from benchmark.problems.timedomain.extended import IDX


def _col(rows, name):
    return rows[:, IDX[name]]


class CoulombFriction(Effect):
    """Constant friction torque ``fc sign(w)``; size = ``fc / (fv w_sync)`` (Coulomb over
    viscous torque at synchronous speed; the paper's motor: 0.41)."""

    name = "coulomb_friction"
    size_name = "fc_over_viscous"
    realistic = (0.2, 1.5)
    extra_names = ("fc_over_viscous",)
    physics = "constant friction torque fc*sign(w) (against the case-1 base without it)"
    shows_in = "stop record: straight-line tail instead of exponential; end of start-up"

    def plant(self, row, size, ctx, form=None):
        row = row.copy()
        row[IDX["fc"]] = size * row[IDX["fv"]] * ctx.w_sync
        return row

    def extra_bounds(self, ctx):
        return np.array([0.0]), np.array([3.0])

    def augment(self, rows, extras, ctx):
        rows = rows.copy()
        # the extra parameter is fc over the viscous torque at synchronous speed, like the size
        rows[:, IDX["fc"]] = extras[:, 0] * rows[:, IDX["fv"]] * ctx.w_sync
        return rows


class DoubleCage(Effect):
    """Second rotor cage (deep bars): the rotor resistance rises with rotor frequency.

    Size ``a``: the high-frequency rotor resistance is ``(1 + a)`` times the low-frequency
    one, which is kept equal to the base ``R_R``; form ``tau2`` (s) is the second cage's
    time constant ``L_sigma2/R2``; form ``ladder: true`` realises it instead as a cage whose
    resistance and leakage both split (a different curve with the same trend)."""

    name = "double_cage"
    size_name = "resistance_rise"
    realistic = (0.3, 1.5)
    extra_names = ("dc_rise", "dc_tau")
    physics = "second rotor cage / deep bars: rotor resistance and leakage depend on rotor frequency"
    shows_in = "early start-up (high slip): speed and current envelope"

    def plant(self, row, size, ctx, form=None):
        form = {**self.form, **(form or {})}
        row = row.copy()
        R_R = row[IDX["R_r1"]]
        tau2 = float(form.get("tau2", 0.004))
        if form.get("ladder", False):
            # deep-bar flavour: cage 1 also takes part of the leakage through a larger share
            a = size * 1.3
            row[IDX["R_r1"]] = (1 + a) * R_R
            row[IDX["R_r2"]] = (1 + a) / a * R_R
            row[IDX["L_sigma2"]] = 0.6 * tau2 * row[IDX["R_r2"]]
            row[IDX["L_sigma"]] *= 1.0 + 0.05 * size
        else:
            row[IDX["R_r1"]] = (1 + size) * R_R
            row[IDX["R_r2"]] = (1 + size) / size * R_R
            row[IDX["L_sigma2"]] = tau2 * row[IDX["R_r2"]]
        return row

    def extra_bounds(self, ctx):
        return np.array([0.02, 3e-4]), np.array([4.0, 0.03])

    def extra_starts(self, ctx):
        return [np.array([0.5, 0.003]), np.array([1.5, 0.001])]

    def augment(self, rows, extras, ctx):
        rows = rows.copy()
        a, tau2 = extras[:, 0], extras[:, 1]
        R_R = rows[:, IDX["R_r1"]].copy()
        rows[:, IDX["R_r1"]] = (1 + a) * R_R
        rows[:, IDX["R_r2"]] = (1 + a) / a * R_R
        rows[:, IDX["L_sigma2"]] = tau2 * rows[:, IDX["R_r2"]]
        return rows


class _Saturation(Effect):
    """A saturating branch: ``i = psi/L (1 + k (|psi|/psi_ref)^n)`` on the extended-model
    fields ``{prefix}_k``, ``{prefix}_psi``, ``{prefix}_exp``. Size ``k``; form ``exponent`` n;
    the augmentation fits ``k`` and ``n`` with the reference flux from the base fit."""

    prefix = ""
    default_exponent = 2.0
    max_exponent = 8.0
    exponent_starts = (2.0, 4.0)

    def plant_reference(self, row, ctx) -> float:
        raise NotImplementedError

    def model_reference(self, ctx) -> float:
        raise NotImplementedError

    def plant(self, row, size, ctx, form=None):
        form = {**self.form, **(form or {})}
        row = row.copy()
        row[IDX[f"{self.prefix}_k"]] = size
        row[IDX[f"{self.prefix}_psi"]] = self.plant_reference(row, ctx)
        row[IDX[f"{self.prefix}_exp"]] = float(form.get("exponent", self.default_exponent))
        return row

    def extra_bounds(self, ctx):
        return np.array([0.0, 1.0]), np.array([2.0, self.max_exponent])

    def extra_starts(self, ctx):
        return [np.array([0.2, n]) for n in self.exponent_starts]

    def augment(self, rows, extras, ctx):
        rows = rows.copy()
        rows[:, IDX[f"{self.prefix}_k"]] = extras[:, 0]
        rows[:, IDX[f"{self.prefix}_exp"]] = extras[:, 1]
        rows[:, IDX[f"{self.prefix}_psi"]] = self.model_reference(ctx)
        return rows


class MainSaturation(_Saturation):
    """Magnetising inductance falls with flux: ``i_M = psi_M/L_M (1 + k (|psi_M|/psi_rated)^n)``.

    Size ``k``: extra magnetising current at rated flux (fraction); form ``exponent`` n."""

    name = "main_saturation"
    size_name = "extra_magnetising_current"
    realistic = (0.1, 0.6)
    extra_names = ("ms_k", "ms_exp")
    physics = "magnetising inductance falls with flux magnitude"
    shows_in = "steady-state / no-load current amplitude, low-order harmonics"
    prefix = "ms"
    default_exponent = 4.0
    max_exponent = 10.0
    exponent_starts = (4.0, 2.0)

    def plant_reference(self, row, ctx):
        return ctx.flux

    def model_reference(self, ctx):
        return ctx.flux


class IronLoss(Effect):
    """Core-loss conductance across the magnetising branch.

    Size ``r = R_fe / (w_e L_M)``: the core-loss resistance relative to the magnetising
    reactance (the larger, the smaller the loss; 20-100 is 1-5 % of a small motor's rating)."""

    name = "iron_loss"
    size_name = "R_fe_over_X_M"
    realistic = (20.0, 100.0)
    extra_names = ("g_fe_pu",)
    physics = "core-loss resistance across the magnetising branch"
    shows_in = "in-phase no-load current"

    def plant(self, row, size, ctx, form=None):
        row = row.copy()
        row[IDX["g_fe"]] = 1.0 / (size * ctx.w_e * row[IDX["L_M"]])
        return row

    def extra_bounds(self, ctx):
        return np.array([0.0]), np.array([0.2])

    def extra_starts(self, ctx):
        return [np.array([0.02])]

    def augment(self, rows, extras, ctx):
        rows = rows.copy()
        rows[:, IDX["g_fe"]] = extras[:, 0] / (ctx.w_e * rows[:, IDX["L_M"]])
        return rows


class TemperatureDrift(Effect):
    """Winding resistances rise with the copper losses during the test (one-body, adiabatic
    over the start-up): ``d theta/dt = P_cu / C``, ``R = R_ref (1 + theta/(234.5 + 20))``.

    Size: the temperature rise over the start-up, K (a motor started repeatedly, or a small
    machine of high current density); form ``cooling``: a cooling time constant in s (0: none)
    is approximated by a smaller effective rise profile."""

    name = "temperature_drift"
    size_name = "temperature_rise"
    size_unit = "K"
    realistic = (4.0, 20.0)
    extra_names = ("heating",)
    physics = "winding resistances rise during the test (copper law, one-body thermal model)"
    shows_in = "residual that grows with test time"

    def plant(self, row, size, ctx, form=None):
        row = row.copy()
        row[IDX["h_th"]] = size / max(ctx.E_cu, 1e-12)
        return row

    def extra_bounds(self, ctx):
        # extra in K of rise over the start-up; up to 60 K
        return np.array([0.0]), np.array([60.0])

    def extra_starts(self, ctx):
        return [np.array([5.0])]

    def augment(self, rows, extras, ctx):
        rows = rows.copy()
        rows[:, IDX["h_th"]] = extras[:, 0] / max(ctx.E_cu, 1e-12)
        return rows


class LeakageSaturation(_Saturation):
    """Leakage inductance falls at high current:
    ``i_s = dpsi/L_sigma (1 + k (|dpsi|/(L_sigma I_peak))^n)``.

    Size ``k``: extra current at the start-up peak's leakage flux (fraction); form
    ``exponent`` n."""

    name = "leakage_saturation"
    size_name = "extra_current_at_peak"
    realistic = (0.1, 0.5)
    extra_names = ("ls_k", "ls_exp")
    physics = "leakage inductance falls at high current"
    shows_in = "start-up current peaks"
    prefix = "ls"
    default_exponent = 2.0
    max_exponent = 8.0
    exponent_starts = (2.0, 4.0)

    def plant_reference(self, row, ctx):
        return row[IDX["L_sigma"]] * ctx.I_peak  # the plant's own leakage

    def model_reference(self, ctx):
        return ctx.L_sigma * ctx.I_peak  # the base fit's leakage


class InverterDrop(Effect):
    """Switch voltage drop and dead time oppose the current sign, per phase: the motor sees
    ``v - U_d sign(i)`` while the data record the ideal switch-state voltages.

    Size: ``U_d`` as a fraction of the DC-link voltage; form ``smooth``: the current (as a
    fraction of the start-up peak) over which the sign changes (0: a hard sign)."""

    name = "inverter_drop"
    size_name = "drop_over_dc_link"
    realistic = (0.01, 0.03)
    extra_names = ("U_d_pu",)
    physics = "switch voltage drop and dead time oppose the current sign"
    shows_in = "current-zero-crossing distortion, 6k +/- 1 harmonics"

    def plant(self, row, size, ctx, form=None):
        form = {**self.form, **(form or {})}
        row = row.copy()
        row[IDX["U_d"]] = size * ctx.dc_link_voltage
        row[IDX["i_0"]] = float(form.get("smooth", 0.0)) * ctx.I_peak
        return row

    def extra_bounds(self, ctx):
        return np.array([0.0]), np.array([0.08])

    def extra_starts(self, ctx):
        return [np.array([0.01])]

    def augment(self, rows, extras, ctx):
        rows = rows.copy()
        rows[:, IDX["U_d"]] = extras[:, 0] * ctx.dc_link_voltage
        rows[:, IDX["i_0"]] = 0.01 * ctx.I_peak
        return rows
