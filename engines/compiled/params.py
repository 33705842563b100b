"""The parameter vectors the kernels read, by name: each a Layout (engines.compiled.layout) of a
settings' field list (``Layout.of_fields``) less the fields no kernel reads, each with its reason,
plus the values that are no field (dt, the inflow rate). A kernel reads ``prm[CONTACT_PRM.eps_m]``
(numba takes the position as a constant); a caller builds the vector with ``vector``.
tests/compiled/test_params.py fails on a field in neither a layout nor its ``not_read``, and on a
layout name no kernel reads. No numba, no YADE.
"""
import dataclasses

from engines.compiled.layout import Layout
from engines.model.contact import CONTACT_FIELDS
from engines.model.pore_water import WATER_FIELDS, WaterBalance
from engines.model.settings import TIE_FIELDS

# contact_forces' prm: eq 1-13, 26-27 (kn, eta_n, ks, eta_s, mu, f_max, eps_m) and the step dt [s]
CONTACT_PRM = Layout.of_fields("CONTACT_PRM", CONTACT_FIELDS, {
    "spring": "passed as the integer ``spring`` (SPRING_CODE): it chooses the kernel's branch",
    "restitution": "passed as the drive's ``e`` (separation_velocities), with ``adjust``",
    "separation_adjustment": "passed as the drive's ``adjust`` flag",
}, extra=("dt",))

# darcy_flows' wp: E_w (eq 32), the permeabilities k1, k2, k3 (eq 43, drained sides) and the
# inflow rate of PoreWater.inflow_weights (q_w or inflow_velocity, the weights in ``bottom``)
WATER_PRM = Layout.of_fields("WATER_PRM", WATER_FIELDS, {
    "q_w": "in the inflow rate ``inflow`` (PoreWater.inflow_weights), with the weights of the pores",
    "inflow_velocity": "in the inflow rate ``inflow`` (PoreWater.inflow_weights), with the inflow lengths",
    "sides": "in the pores' ``drained`` weights (PoreWater._boundary_masks)",
    "smoothing": "passed as water_step's ``smoothing`` flag",
    "substep": "passed as water_step's ``substep`` flag",
    "transfer": "re-meshing (engines.compiled.pores.REMESH), between water steps",
}, extra=("inflow",))

# tie_forces' tie_prm: k'_s [N/m], eta'_s [N s/m] of the side-wall ties (Fig. 27)
TIE_PRM = Layout.of_fields("TIE_PRM", TIE_FIELDS, {})

# darcy_update's balance and the drives' totals [m^2]: the WaterBalance books a water step adds to
BALANCE = Layout.of_fields("BALANCE", [f.name for f in dataclasses.fields(WaterBalance)], {
    "initial": "the water at the start: no step adds to it",
    "remesh_change": "booked by re-meshing (PoreWater.remesh), not by a water step",
    "remesh_excess_change": "booked by re-meshing (PoreWater.remesh), not by a water step",
    "remesh_excess_edge": "booked by re-meshing (PoreWater.remesh), not by a water step",
})

# water_step's lam: the Gershgorin bound lambda [1/s] of the first and of the last sub-step's flows
LAM = Layout("LAM", ("first", "last"))

PARAMETERS = (CONTACT_PRM, WATER_PRM, TIE_PRM, BALANCE)  # the layouts of field lists (tests/compiled/test_params.py)


def balance_of(b):
    """The BALANCE vector (3,) [m^2] of the WaterBalance b."""
    return BALANCE.vector(b)


def book_balance(b, totals, add=False):
    """WaterBalance b's books set from the BALANCE vector ``totals`` [m^2] (``add``: added to them)."""
    for name, value in zip(BALANCE.names, totals.tolist()):
        setattr(b, name, getattr(b, name) + value if add else value)
