"""``robustgait robot init``: a robot's spec written from its model file (``docs/robots.md``, "Your robot") — the
model's analysis (:mod:`robustgait.inspection`), its default gait generated (:mod:`robustgait.gaitgen`), its timestep
chosen by walking that gait (:mod:`robustgait.sim`, the certificate's orbit rule), and the commented TOML; and
``robot check``'s ``timestep`` check, which walks it too. Above the pipeline it uses, so that the model's analysis,
below the certificate, does not reach up to it.

=============== ==========================================================================================
module          owns
=============== ==========================================================================================
``draft``       everything a spec drafted from a model says, gathered from :mod:`robustgait.inspection`
``timestep``    the timestep by accuracy: the default gait walked at a step and at half of it; robot check's
                ``timestep`` check
``writer``      the commented spec TOML and robot init's summary
``init``        robot init end to end: the draft, its timestep chosen by walking, the gains drafted at it
=============== ==========================================================================================
"""
