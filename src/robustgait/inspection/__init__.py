"""Robot inspection: a spec written from a robot's model file (``robustgait robot init``) and a spec checked
against its model (``robustgait robot check``); ``docs/robots.md``, "Your robot".

=============== ==========================================================================================
module          owns
=============== ==========================================================================================
``model``       the compiled model, its floating base, the standing posture, geom geometry, the kinematic tree
``discover``    the legs, soles, floor, joints (ranges, torque limits and where each came from)
``mirror``      the left/right relabeling from names and joint axes, verified by reflecting the model
``gains``       PD gains from each joint's reflected inertia, their torque cap and discrete-time stability
``scale``       the robot's gait parameters, bounds and margins scaled by its leg length and mass
``draft``       everything a spec drafted from a model says (robot init), gathered from the modules above
``timestep``    the timestep by accuracy: the default gait walked at a step and at half of it; robot check's
                ``timestep`` check
``writer``      the commented spec TOML and robot init's summary
``robotinit``   robot init end to end: the draft, its timestep chosen by walking, the gains drafted at it
``check``       the checks of a spec: mirror, standing, soles, tracking, torque limits
=============== ==========================================================================================
"""
