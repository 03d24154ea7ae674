"""An independent validation plant: induction-motor start-up data written from the physics.

Why it exists. A diagnosis validated only on data made by the project's own effect models
measures how well a model fits itself, not whether the diagnosis finds a real gap. This
package makes data with a plant that shares no code with ``benchmark`` (nor ``plugins`` or
the other ``synthetic`` modules): it imports only the standard library, numpy, scipy, numba
and yaml, so a mistake in the project's model cannot reappear here unnoticed. What it needs
of the project's conventions it repeats on purpose, and says so: the amplitude-invariant
Clarke transform (:func:`inverter.clarke`), the referral to the project's ``Lr = Ls``
parameters (:meth:`machine.TMachine.referred`) and a CSV/YAML writer for the data-set folder
format (:func:`dataset.write_dataset`).

What it models (SI units, stator-fixed alpha-beta frame, amplitude-invariant Clarke,
``x_a = 2/3 (x_R - (x_S + x_T)/2)``, ``x_b = (x_S - x_T)/sqrt(3)``, torque
``3/2 p (psi_s x i_s)``):

* the machine's T-equivalent circuit with flux linkages of every winding as states: stator,
  one or more rotor loops (single cage, double cage, deep-bar ladder) and an optional
  iron-loss winding, with a magnetising curve and saturable leakage paths solved
  consistently at every evaluation (:mod:`electrical`, :mod:`curves`, :mod:`rotor`);
* shaft mechanics with viscous and Coulomb friction (stiction), load torques and a
  two-mass coupling (:mod:`mechanics`), winding temperatures (:mod:`thermal`);
* supplies: a grid direct-on-line start (harmonics, unbalance, source impedance, staggered
  and bouncing contactor poles, pre-trigger), a six-step inverter and open-loop V/f PWM, with
  device drops and dead time (:mod:`supply`, :mod:`inverter`); a free stop;
* sensors and noise (:mod:`sensors`, :mod:`probes`), the effect catalogue (:mod:`effects`,
  :mod:`sensor_effects`, :mod:`effect_base`), motor presets (:mod:`motors`), data sets and
  blind draws (:mod:`dataset`, :mod:`blind`).

Every effect has *development* forms (those the project's diagnosis was developed on) and
*held-out* forms (second physical forms, for scoring only), split in one place,
:mod:`forms`; a draw takes the development forms unless told ``forms="heldout"`` or
``"all"`` (``docs/effect_forms.md`` lists every form with its equations and ranges).

How it differs from the identification model: flux states instead of stator current and
rotor flux, its own RK4 with a step several times shorter than the sample time, the input as
the physics gives it (gate patterns, a continuous grid EMF) instead of held or interpolated
samples, and the record picked from that finer trajectory (:mod:`integrate`).

Typical use::

    from synthetic.independent import make_spec, make_dataset, write_dataset
    ds = make_dataset(make_spec("paper_1kw", "dol", ["double_cage"], seed=3, stop=20))
    write_dataset(ds, "data/indep_dc")

or ``python -m synthetic.independent --motor paper_1kw --scenario dol --effects double_cage
--seed 3 --out data/indep_dc --stop``.
"""

from synthetic.independent.blind import draw_blind_set
from synthetic.independent.dataset import Dataset, make_dataset, make_spec, write_dataset
from synthetic.independent.effects import EFFECTS, get_effect
from synthetic.independent.forms import DEVELOPMENT, FORM_SETS, HELDOUT, forms_of
from synthetic.independent.machine import TMachine
from synthetic.independent.motors import PRESETS, Motor, get_motor
from synthetic.independent.plant import Plant

__all__ = ["DEVELOPMENT", "EFFECTS", "FORM_SETS", "HELDOUT", "PRESETS", "Dataset", "Motor", "Plant", "TMachine",
           "draw_blind_set", "forms_of", "get_effect", "get_motor", "make_dataset", "make_spec", "write_dataset"]
