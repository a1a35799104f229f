"""Robot inspection: what a robot's model file says (legs, soles, mirror, gains, scale: the analysis
:mod:`robustgait.robotinit` drafts a spec from) and a spec checked against its model (``robustgait robot check``);
``docs/robots.md``, "Your robot".

=============== ==========================================================================================
module          owns
=============== ==========================================================================================
``model``       the compiled model, its floating base, the standing posture, geom geometry, the kinematic tree
``discover``    the legs, soles, floor, joints (ranges, torque limits and where each came from)
``mirror``      the left/right relabeling from names and joint axes, verified by reflecting the model
``gains``       PD gains from each joint's reflected inertia, their torque cap and discrete-time stability
``scale``       the robot's gait parameters, bounds and margins scaled by its leg length and mass
``check``       the checks of a spec: mirror, standing, soles, tracking, torque limits
=============== ==========================================================================================
"""
