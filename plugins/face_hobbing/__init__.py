"""The face-hobbing chain the Klingelnberg machine models share (seed 001; seed 003).

Cyclo-palloid (:mod:`gearopt_plugins.cyclo_palloid`, a dual head) and epicycloid
(:mod:`gearopt_plugins.epicycloid`, one head radius per flank) differ in their cutter heads
only. Past the head, the chain is stated once here, on settings, never on a design:

:mod:`.settings`
    From a head to the machine: the slope angle, eccentricity, machine distance and cradle
    angle kernels (eqs 5-14, 33-36), the work's settings and roll ratios (``WorkSettings``:
    eqs 25, 37, 49-59) and each blade system's disk on the cradle (``CutterDisk``: eqs 13-14,
    28-29, 34-35).
:mod:`.family`
    One blade system (``BladeSystem``) and its generating family r(u, theta, psi_cr) with the
    meshing function (eqs 2-31), vectorised, complex-step safe.
:mod:`.generation`
    A blade system from the settings, the turn of a flank onto tooth 0 (the outer blades' lead)
    and the flanks as envelopes on a FlankMap grid, in one batch.

This package holds no plugin (no hook implementation): the models are the plugins.
"""
