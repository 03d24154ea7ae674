"""Time-domain effects: each one class, acting on extended-model rows.

Sizes are in the units each class documents; ``realistic`` ranges are the defaults of the
YAMLs in ``conf/effect/``. ``form`` options vary how the plant realises an effect (exponent of
a saturation curve, hard or smooth inverter drop, a double cage or a three-section deep-bar
ladder...), so that a diagnosis tuned to one form is checked on others; each class draws its
own random variation of form for blind tests (``FORM_DRAWS``, :meth:`Effect.random_form`).

The augmentations are meant to fit the physics whatever the maker's formula (checked against
the independent plant, ``synthetic/independent``): the magnetising curve is a monotone sum of
two power laws (a soft quadratic knee plus a sharper term of free exponent: it follows Frohlich,
arctan and tabulated curves), the rotor impedance varies with rotor frequency through a second
branch while the low-slip resistance and leakage stay the base model's (two cages or a deep-bar
ladder), the iron-loss conductance sits anywhere between the stator EMF and the rotor flux node,
and the leakage saturates towards a linear floor (reported as an inductance-current curve by
:meth:`LeakageSaturation.leakage_curve`).

The bench effects (sensors, shaft) live in :mod:`benchmark.problems.timedomain.bench_effects`,
the load in :mod:`~benchmark.problems.timedomain.load_effect`, the winding's heating in
:mod:`~benchmark.problems.timedomain.temperature_effect`; all are re-exported here.
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
    extra_units = ("p.u. of fv w_sync",)
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
    resistance and leakage both split (a different curve with the same trend).

    The augmentation fits a rotor of three parallel loops (cage 1 without leakage, loops 2 and 3
    with their own time constants): the impedance of a double cage exactly, and that of a deep
    bar (a distributed ladder of bar slices) to within a few parts in a million of its magnitude
    over rotor frequencies 0-50 Hz, where two loops leave up to about 0.3 % (several times the
    current noise of a direct start)."""

    name = "double_cage"
    size_name = "resistance_rise"
    realistic = (0.3, 1.5)
    extra_names = ("dc_rise", "dc_tau", "dc_share3", "dc_tau3")
    #: Two rotor loops: the third came with 91ed134 (the plant's deep bars of 3-6 slices, where
    #: two loops left 1.7-2.4 % up to the 13th harmonic).
    FIRST_FORM = {"dc_share3": 0.0, "dc_tau3": 5e-4}
    extra_units = ("p.u. of low-slip R_R", "s", "fraction of loops 2+3 conductance", "s")
    FORM_DRAWS = {"ladder": {"choice": [False, True]}, "tau2": [0.002, 0.008]}
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
        return np.array([0.02, 3e-4, 0.0, 1.5e-4]), np.array([8.0, 0.03, 0.5, 0.03])

    def extra_starts(self, ctx):
        # two cages (loop 3 absent), then a deep bar's typical three-loop shape
        return [np.array([0.5, 0.003, 0.0, 5e-4]), np.array([1.5, 0.001, 0.0, 5e-4]),
                np.array([3.0, 0.005, 0.1, 7e-4])]

    def augment(self, rows, extras, ctx):
        """Cage 1 ``(1 + a) R_R`` (no leakage); the leaky loops share the conductance
        ``a/((1 + a) R_R)``, loop 2 ``1 - q`` of it with time constant ``tau2``, loop 3 ``q`` with
        ``tau3`` (absent at ``q = 0``): the rotor resistance rises from ``R_R`` (low slip)
        towards ``(1 + a) R_R`` at high rotor frequency. The low-slip leakage,
        ``L_sigma + R_R a/(1 + a) ((1 - q) tau2 + q tau3)``, is kept at the base model's
        ``L_sigma`` (the common leakage is reduced by the loops' share), so that the base
        parameters keep their low-slip meaning; rows where that is impossible are invalid."""
        rows = rows.copy()
        a, tau2, q, tau3 = extras[:, 0], extras[:, 1], extras[:, 2], extras[:, 3]
        R_R = rows[:, IDX["R_r1"]].copy()
        leaky = a / ((1 + a) * R_R)  # S, conductance of loops 2 and 3 together
        rows[:, IDX["R_r1"]] = (1 + a) * R_R
        rows[:, IDX["R_r2"]] = 1.0 / ((1 - q) * leaky)
        rows[:, IDX["L_sigma2"]] = tau2 * rows[:, IDX["R_r2"]]
        has3 = q > 0
        R3 = np.where(has3, 1.0 / np.where(has3, q * leaky, 1.0), 0.0)
        rows[:, IDX["R_r3"]] = R3
        rows[:, IDX["L_sigma3"]] = np.where(has3, tau3 * R3, 0.0)
        L_common = rows[:, IDX["L_sigma"]] - R_R * a / (1 + a) * ((1 - q) * tau2 + q * tau3)
        rows[:, IDX["L_sigma"]] = np.where(L_common > 0, L_common, np.nan)
        return rows

    def describe_fit(self, extras, ctx, base=None):
        a, tau2, q, tau3 = (float(v) for v in np.ravel(extras)[:4])
        return {"resistance_rise": a, "cage2_time_constant_s": tau2, "loop3_share": q,
                "loop3_time_constant_s": tau3,
                "R_ratio_at_supply_frequency": float(self.resistance_ratio(a, tau2, ctx.w_e, q, tau3))}

    @staticmethod
    def resistance_ratio(a: float, tau2: float, w: float, q: float = 0.0, tau3: float = 0.0) -> float:
        """Rotor resistance at rotor angular frequency ``w`` (rad/s) over its low-slip value."""
        y = 1.0 / (1 + a) + a / (1 + a) * ((1 - q) / (1 + 1j * w * tau2) + q / (1 + 1j * w * tau3))
        return float((1.0 / y).real)


class _Saturation(Effect):
    """A saturating branch: ``i = psi/L (1 + k (|psi|/psi_ref)^n)`` on the extended-model
    fields ``{prefix}_k``, ``{prefix}_psi``, ``{prefix}_exp``. Size ``k``; form ``exponent`` n;
    the augmentation fits ``k`` and ``n`` (and, in subclasses, a third shape parameter) with the
    reference flux from the base fit."""

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

    Size ``k``: extra magnetising current at rated flux (fraction); form ``exponent`` n.

    Augmentation: a flexible monotone curve, ``i_M = psi_M/L_M (1 + k x^n + k2 x^2)`` with
    ``x = |psi_M|/psi_rated`` and non-negative ``k, k2`` (a soft quadratic knee plus a sharper
    term of free exponent ``n`` in 3-16: Frohlich, arctan and tabulated B-H curves fit it over
    the fluxes a start-up reaches); ``L_M`` stays the unsaturated value. The saturating branch
    sits at the magnetising node of a T circuit (the extended model's T mode) whose leakage is
    shared ``ms_stator_leak = Lls/(Lls + Llr)`` on the stator side, 0.005-0.95: where the iron
    saturates in a real machine, between the stator and rotor leakages, which the
    inverse-Gamma node (all leakage on the rotor side of the node's inductance, share 1)
    cannot represent once ``Lm`` varies (on the independent plant the inverse-Gamma node left a
    third of the gap). A Gamma model that saturates with the stator flux (motulator's induction
    machine: all leakage on the rotor side, share 0) sits at the other end. With the share
    limited to 0.25 (``Llr/Lls <= 3``) the diagnosis of a direct-on-line start of motulator's
    saturated 2.2 kW example machine (``S = 7``) stopped at 1.54 times the noise (from 1.89,
    ``partly_explained``); with the Gamma end in reach, 1.011 (six-step: 3.02 -> 0.98), the
    exponent found 7.0 (``tests/problems/timedomain/test_gamma_saturation.py``). Beside a
    saturating leakage (``leakage_saturation`` in the same model) the curve sits at the
    inverse-Gamma node and the share is not determined (standard error nan): the T mode has
    no saturating leakage (``tests/problems/timedomain/test_two_saturations.py``)."""

    name = "main_saturation"
    size_name = "extra_magnetising_current"
    realistic = (0.1, 0.6)
    extra_names = ("ms_k", "ms_exp", "ms_k2", "ms_stator_leak")
    extra_units = ("p.u. of psi_rated/L_M", "-", "p.u. of psi_rated/L_M", "fraction of leakage (stator side)")
    physics = "magnetising inductance falls with flux magnitude"
    shows_in = "steady-state / no-load current amplitude, low-order harmonics"
    prefix = "ms"
    default_exponent = 4.0
    FORM_DRAWS = {"exponent": {"choice": [2.0, 4.0, 6.0]}}

    def plant_reference(self, row, ctx):
        return ctx.flux

    def model_reference(self, ctx):
        return ctx.flux

    def extra_bounds(self, ctx):
        return np.array([0.0, 1.0, 0.0, 0.005]), np.array([3.0, 16.0, 2.0, 0.95])

    def extra_starts(self, ctx):
        # leakage shared equally (0.5), mostly on the stator side (0.83), and the Gamma-like
        # stator-flux saturation of motulator's machine (0.05, its exponent 7)
        return [np.array([0.1, 6.0, 0.05, 0.5]), np.array([0.2, 10.0, 0.0, 0.5]), np.array([0.02, 4.0, 0.15, 0.5]),
                np.array([0.15, 1.0, 0.0, 0.5]), np.array([0.1, 6.0, 0.05, 1.0 / 1.2]),
                np.array([0.3, 7.0, 0.0, 0.05])]

    @staticmethod
    def split_of(stator_leak):
        """``Llr/Lls`` of the T circuit (the extended model's ``t_split``) from the stator side's
        share of the leakage ``Lls/(Lls + Llr)``."""
        return (1.0 - stator_leak) / stator_leak

    def augment(self, rows, extras, ctx):
        rows = rows.copy()
        rows[:, IDX["ms_k"]] = extras[:, 0]
        rows[:, IDX["ms_exp"]] = extras[:, 1]
        rows[:, IDX["ms_k2"]] = extras[:, 2]
        rows[:, IDX["ms_exp2"]] = 2.0
        rows[:, IDX["ms_psi"]] = self.model_reference(ctx)
        rows[:, IDX["t_split"]] = self.split_of(extras[:, 3])
        return rows

    def magnetising_curve(self, extras, flux, ctx, L_M=None):
        """Magnetising current (A) at flux linkages ``flux`` (Wb) of the fitted curve."""
        k, n, k2 = (float(v) for v in np.ravel(extras)[:3])
        L_M = ctx.L_M if L_M is None else float(L_M)
        x = np.abs(np.asarray(flux, float)) / ctx.flux
        return np.asarray(flux, float) / L_M * (1.0 + k * x**n + k2 * x**2)

    def describe_fit(self, extras, ctx, base=None):
        k, n, k2 = (float(v) for v in np.ravel(extras)[:3])
        drop = {f"L_M_secant_over_unsaturated_at_{int(f * 100)}pct_flux": float(1.0 / (1.0 + k * f**n + k2 * f**2))
                for f in (0.5, 0.8, 1.0, 1.1)}
        share = float(np.ravel(extras)[3])
        return {"ms_k": k, "ms_exp": n, "ms_k2": k2, "stator_leakage_share": share,
                "Llr_over_Lls": float(self.split_of(share)), **drop}


class IronLoss(Effect):
    """Core-loss conductance across the magnetising branch.

    Size ``r = R_fe / (w_e L_M)``: the core-loss resistance relative to the magnetising
    reactance (the larger, the smaller the loss; 20-100 is 1-5 % of a small motor's rating)."""

    name = "iron_loss"
    size_name = "R_fe_over_X_M"
    realistic = (20.0, 100.0)
    size_falls_with_effect = True  # the smallest real core loss has the largest R_fe/X_M, 100
    extra_names = ("g_fe_pu", "fe_position")
    extra_units = ("p.u. of 1/(w_e L_M)", "fraction at stator EMF")
    FORM_DRAWS = {"position": [0.0, 1.0]}
    physics = "core-loss resistance across the magnetising branch"
    shows_in = "in-phase no-load current"

    def plant(self, row, size, ctx, form=None):
        """Form ``position`` (0-1): where the loss resistance sits, 0 across the rotor flux node
        (the default), 1 across the stator EMF, between: shared."""
        form = {**self.form, **(form or {})}
        pos = float(form.get("position", 0.0))
        row = row.copy()
        g = 1.0 / (size * ctx.w_e * row[IDX["L_M"]])
        row[IDX["g_fe"]] = (1.0 - pos) * g
        row[IDX["g_fe_s"]] = pos * g
        return row

    def extra_bounds(self, ctx):
        return np.array([0.0, 0.0]), np.array([0.2, 1.0])

    def extra_starts(self, ctx):
        return [np.array([0.02, 0.5]), np.array([0.02, 0.0]), np.array([0.02, 1.0])]

    def fitted_size(self, extras, ctx):
        """``R_fe/(w_e L_M)`` of the fitted conductance, ``1/g_fe_pu`` (inf for none): where the
        loss sits along the leakage does not change how large it is."""
        g = float(np.ravel(extras)[0])
        return 1.0 / g if g > 0 else float("inf")

    def augment(self, rows, extras, ctx):
        """Conductance ``g_fe_pu/(w_e L_M)``, a share ``fe_position`` of it across the stator
        EMF and the rest across the rotor flux node: a loss resistance anywhere along the
        leakage (a T circuit's magnetising node, an iron-loss winding, the terminals)."""
        rows = rows.copy()
        g = extras[:, 0] / (ctx.w_e * rows[:, IDX["L_M"]])
        pos = extras[:, 1]
        rows[:, IDX["g_fe"]] = (1.0 - pos) * g
        rows[:, IDX["g_fe_s"]] = pos * g
        return rows


class LeakageSaturation(_Saturation):
    """Leakage inductance falls at high current:
    ``i_s = dpsi/L_sigma (1 + k (|dpsi|/(L_sigma I_peak))^n)``.

    Size ``k``: extra current at the start-up peak's leakage flux (fraction); form
    ``exponent`` n, ``floor`` (share of the leakage that does not saturate, default 0).

    Augmentation: ``i_s = dpsi/(L_sigma l(x))``, ``l = f + (1 - f)/(1 + k x^n)``, ``x =
    |dpsi|/(L_sigma I_peak)``: the leakage falls from ``L_sigma`` (small currents: the
    unsaturated value) towards the linear floor ``f L_sigma`` (slot body, end windings).
    :meth:`leakage_curve` gives the leakage inductance as a function of current."""

    name = "leakage_saturation"
    size_name = "extra_current_at_peak"
    realistic = (0.1, 0.5)
    extra_names = ("ls_k", "ls_exp", "ls_floor")
    extra_units = ("-", "-", "p.u. of unsaturated L_sigma")
    physics = "leakage inductance falls at high current"
    shows_in = "start-up current peaks"
    prefix = "ls"
    default_exponent = 2.0
    FORM_DRAWS = {"exponent": {"choice": [1.5, 2.0, 3.0]}, "floor": {"choice": [0.0, 0.0, 0.3]}}

    def plant_reference(self, row, ctx):
        return row[IDX["L_sigma"]] * ctx.I_peak  # the plant's own leakage

    def model_reference(self, ctx):
        return ctx.L_sigma * ctx.I_peak  # the base fit's leakage

    def plant(self, row, size, ctx, form=None):
        form = {**self.form, **(form or {})}
        row = super().plant(row, size, ctx, form)
        row[IDX["ls_floor"]] = float(form.get("floor", 0.0))
        return row

    def extra_bounds(self, ctx):
        # k up to 1000: a sharp knee well above the rated current (the independent plant's
        # lorentzian leakage, knee 2.7-7.9 times the rated current) needs k x^n ~ 1 at x ~ 0.2,
        # k = 300-440 with n ~ 3.8; with k <= 20 the fit sat at the bound (plant blind set 52/26:
        # k 20, n 1.44, 6.62 times the noise left; k 439, n 3.78: 2.17)
        return np.array([0.0, 1.0, 0.0]), np.array([1000.0, 8.0, 0.9])

    def extra_starts(self, ctx):
        return [np.array([0.3, 2.0, 0.0]), np.array([2.0, 2.0, 0.3]), np.array([2.0, 4.0, 0.4])]

    def augment(self, rows, extras, ctx):
        rows = super().augment(rows, extras, ctx)
        rows[:, IDX["ls_floor"]] = extras[:, 2]
        return rows

    def leakage_curve(self, extras, currents, ctx, L_sigma: float | None = None) -> np.ndarray:
        """Secant leakage inductance (H) at stator current amplitudes ``currents`` (A) for the
        fitted extras; ``L_sigma``: the fitted unsaturated leakage (default: the base fit's)."""
        k, n, fl = (float(v) for v in np.ravel(extras)[:3])
        L0 = ctx.L_sigma if L_sigma is None else float(L_sigma)
        ref = ctx.L_sigma * ctx.I_peak
        i = np.abs(np.asarray(currents, float))

        def ell(x):
            return fl + (1.0 - fl) / (1.0 + k * x**n)

        # current(flux) = flux/(L0 ell(flux/ref)) is increasing: bisection on the flux
        lo = np.zeros_like(i)
        hi = np.maximum(L0 * i, 1e-30)
        while True:  # widen until the current at hi exceeds i
            short = hi / (L0 * ell(hi / ref)) < i
            if not np.any(short):
                break
            hi = np.where(short, 2.0 * hi, hi)
        hi = hi / max(fl, 1e-6) if fl > 0 else hi
        hi = np.maximum(hi, L0 * i)
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            above = mid / (L0 * ell(mid / ref)) > i
            hi = np.where(above, mid, hi)
            lo = np.where(above, lo, mid)
        flux = 0.5 * (lo + hi)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(i > 0, flux / np.where(i > 0, i, 1.0), L0)

    def describe_fit(self, extras, ctx, base=None):
        """The fitted leakage at currents scaled to the record: 15 %, 50 % and 100 % of the
        start-up peak (like L(13 A), L(90 A) of a 90 A start), and the floor."""
        L0 = None if not base else base.get("Le")
        fr = (0.15, 0.5, 1.0)
        cur = [f * ctx.I_peak for f in fr]
        L = self.leakage_curve(extras, cur, ctx, L0)
        out = {"ls_k": float(np.ravel(extras)[0]), "ls_exp": float(np.ravel(extras)[1]),
               "ls_floor": float(np.ravel(extras)[2])}
        for c, v in zip(cur, L, strict=True):
            out[f"L_sigma_at_{c:.3g}A"] = float(v)
        out["L_sigma_ratio_peak_over_15pct"] = float(L[-1] / L[0])
        return out


class InverterDrop(Effect):
    """Switch voltage drop and dead time oppose the current sign, per phase: the motor sees
    ``v - U_d sign(i)`` while the data record the ideal switch-state voltages.

    Size: ``U_d`` as a fraction of the DC-link voltage; form ``smooth``: the current (as a
    fraction of the start-up peak) over which the sign changes (0: a hard sign)."""

    name = "inverter_drop"
    size_name = "drop_over_dc_link"
    realistic = (0.01, 0.03)
    extra_names = ("U_d_pu",)
    extra_units = ("p.u. of DC-link voltage",)
    physics = "switch voltage drop and dead time oppose the current sign"
    shows_in = "current-zero-crossing distortion, 6k +/- 1 harmonics"
    FORM_DRAWS = {"smooth": {"choice": [0.0, 0.02, 0.05]}}

    def applies_to(self, facts):
        if facts.get("dc_link_voltage") or str(facts.get("input_hold") or "") == "zoh":
            return None
        return "no inverter: neither a DC-link voltage nor inverter-held (zoh) voltages in the record"

    def plant(self, row, size, ctx, form=None):
        form = {**self.form, **(form or {})}
        row = row.copy()
        row[IDX["U_d"]] = size * ctx.dc_link_voltage
        row[IDX["i_0"]] = float(form.get("smooth", 0.0)) * ctx.I_peak
        return row

    def extra_bounds(self, ctx):
        return np.array([0.0]), np.array([0.08])

    def extra_starts(self, ctx):
        """The smallest realistic drop, and none (the model it grows from: its fit starts where
        the smaller model ended, so it never ends worse in sample). From the first alone, one
        start, the fit is a lottery of rounding: on the calibration's development plant set 8 (a
        double cage and a drop) the drop's fold fits ended at 15-21 million from 82-95 million
        (the base's fold fits about 4 million) after a change of the free coast's last bits, and
        nothing was named; from none as well, the drop explains 99.7 % of the excess."""
        return [np.array([0.01]), np.array([0.0])]

    def augment(self, rows, extras, ctx):
        rows = rows.copy()
        rows[:, IDX["U_d"]] = extras[:, 0] * ctx.dc_link_voltage
        rows[:, IDX["i_0"]] = 0.01 * ctx.I_peak
        return rows


from benchmark.problems.timedomain.bench_effects import (  # noqa: E402  (re-exported)
    ChannelDelay,
    CurrentSensorSaturation,
    SpeedSensorGain,
    TwoMass,
)
from benchmark.problems.timedomain.load_effect import LoadTorque  # noqa: E402  (re-exported)
from benchmark.problems.timedomain.offset_effect import SensorOffset  # noqa: E402  (re-exported)
from benchmark.problems.timedomain.temperature_effect import TemperatureDrift  # noqa: E402  (re-exported)

__all__ = ["ChannelDelay", "CoulombFriction", "CurrentSensorSaturation", "DoubleCage", "InverterDrop", "IronLoss",
           "LeakageSaturation", "LoadTorque", "MainSaturation", "SensorOffset", "SpeedSensorGain", "TemperatureDrift",
           "TwoMass"]
