"""Mesh-cycle analyses on the clearance field: TCA, contact pattern, backlash, ease-off.

Everything here works on :class:`gearopt.contact.ClearanceField` objects and knows nothing of
machines. Conventions (docs/architecture.md, "Drive and coast", "Pattern coordinates", "Frames
and signs"): the drive side is the pinion's convex flank driving the gear's concave flank, the
coast side the pinion's concave driving the gear's convex. TE is in arcsec of gear rotation,
negative when the driven gear lags, shifted so its maximum over the mesh is 0. Pattern
coordinates on the pinion flank projected to the axial plane: ``face`` from the toe (0) toward
the heel, ``profile`` from the root (0) toward the top.

Definitions used by the outputs:

- positions: ``positions`` pinion angles over ``cycles`` angular pitches, centred on the mean
  position, in the pinion's direction of motion (``phi1_deg``);
- at each position the ``pairs`` tooth pairs nearest the mesh centre; the carrying pair is the
  one on which the gear lags least;
- hand-over: where the TE curves of two successive pairs intersect, solved on the clearance
  field, not read off the samples: where the samples around it are interior contacts (smooth
  lags), guessed where the cubic interpolants of the two pairs' sampled lags cross, then the
  root of the parabola through the lag differences evaluated at the guess and an eighth of a
  step to either side (a guess further off is evaluated anew); otherwise (edge contact) a
  secant step, the parabola through three differences and a last secant step; peak-to-peak
  TE = the TE maximum (refined by parabolas) minus the TE at the hand-over, or minus a lower
  sampled value if any;
- instantaneous contact zone: the nodes within the marking compound of the mating flank; the
  contact path is the zone's centroid (weights ``compound - separation``, so a paraboloid's
  centroid is its vertex and a line contact's is its middle) along the carrying pair's cycle;
- the zones' chords, on the refined field (:mod:`gearopt.mesh.zone`): at the position midway
  between the carrying pair's hand-overs, the major axis is the zone's chord through the
  contact point along the least curvature of the separation's quadratic form, the mean
  contact point M its middle (seed 003 section 6), the minor axis the chord across it through
  M; width = the extent across the path at M of the pattern the zones sweep (at a point the
  least separation over the motion: over a pair's positions, the parabola through the least
  and its neighbours; the path's direction: the zones' middles a quarter step either side of
  M); bias =
  the contact line's extension along the face (seed 003 section 6): the face coordinate of the
  contact point where the pair leaves contact inside the flanks minus where it enters (the ends
  of its contact interval: bracketed by bisection on the engine's edge flag to an eighth of a
  position step, the points it can visit evaluated at once, then moved to where the tangency
  point -- the solution of the tangency equations, :mod:`gearopt.newton_tca` -- leaves the
  flanks, but for line contact; the carrying cycle's ends when the contact never leaves the
  flanks' interior); ``center_offset_mm`` = M minus the flank centre C (the mean cone
  distance, mid working depth: h = (a1 - a2) / 2 with a the mean addenda);
- a flat TE (the lag within 0.1 arcsec over the interior contacts) is a line contact's or a
  point contact's whose contact points stay on one conjugate line (seed 003 section 7.1, case
  A), told apart by the marking compound's zone at the middle of the contact interval: a point
  contact's closes on the flanks along its valley, where the least separation across the
  major axis rises as half the least curvature times the distance squared; a line contact's
  valley is its contact line, the separation on it the interpolants' error, far below any
  compound (:meth:`gearopt.mesh.zone.Zones.closed`). A point contact's interval ends are the
  tangency point's exits like any other's, M's position is the middle of the contact
  interval (its hand-overs lie in noise) and the outline's stations are its tangency points
  (:meth:`gearopt.mesh.zone.Zones.tangency_points`); a line contact, whose tangency point is
  not unique, keeps the ends the edge flag brackets and M midway between hand-overs;
- the zones and the tangency point's exit end at the pinion's generated boundary, continuous
  across the grid (:attr:`gearopt.flank.FlankMap.lowest_profile_mm`: the envelope's fold
  solved per face column, 0.3 mm above it, or the blade tip's line), not at its nodes; the
  outline (``outline_mm``) is the pattern's on the refined field
  (:meth:`gearopt.mesh.zone.Zones.outline`);
- contact ratio: the pinion rotation over which a pair's contact stays inside the flanks (not
  at an edge), over the angular pitch (sampled on beyond the analysed range when a pair is
  still in contact at its ends, up to 1.5 pitches more).

Modules:

- :mod:`gearopt.mesh.frame`: :class:`ToothFrame` (pattern coordinates), :func:`path_angle`;
- :mod:`gearopt.mesh.pattern`: separations and zone centroids on the nodes;
- :mod:`gearopt.mesh.zone`: the zones' chords on the refined field
  (:class:`~gearopt.mesh.zone.Zones`);
- :mod:`gearopt.mesh.handover`: the hand-over's search (:class:`~gearopt.mesh.handover.HandOver`);
  its iteration's step compiled in :mod:`gearopt.mesh.handover_kernels`;
- :mod:`gearopt.mesh.side`: :class:`SideCycle`, one side's mesh cycle;
- :mod:`gearopt.mesh.cycle`: :class:`ToothContact`, :class:`MeshCycle` (every side's joint
  evaluations), :func:`tooth_contacts`, :func:`tooth_contact`;
- :mod:`gearopt.mesh.backlash`, :mod:`gearopt.mesh.ease_off`: :func:`backlash`,
  :func:`ease_off`;
- :mod:`gearopt.mesh.pair`: :class:`MeshedPair` (:func:`mesh_pair`), :class:`PairCurve`.
"""

from gearopt.mesh.backlash import Backlash, backlash
from gearopt.mesh.cycle import MeshCycle, ToothContact, tooth_contact, tooth_contacts
from gearopt.mesh.ease_off import EaseOff, ease_off
from gearopt.mesh.frame import ARCSEC, ToothFrame, path_angle
from gearopt.mesh.pair import MeshedPair, PairCurve, mesh_pair
from gearopt.mesh.side import FLAT_ARCSEC, SideCycle

__all__ = [
    "ARCSEC",
    "FLAT_ARCSEC",
    "Backlash",
    "EaseOff",
    "MeshCycle",
    "MeshedPair",
    "PairCurve",
    "SideCycle",
    "ToothContact",
    "ToothFrame",
    "backlash",
    "ease_off",
    "mesh_pair",
    "path_angle",
    "tooth_contact",
    "tooth_contacts",
]
