"""The engine a simulation runs on, chosen by ``sim.controller`` (``docs/simulation.md``, ``docs/feedback.md``).

* ``pd`` — :class:`~robustgait.sim.engine.StepEngine`: the joint PD (+ feedforward) folded into MuJoCo's position
  servos and rolled out open loop by ``mujoco.rollout``, the fastest engine.
* ``passivity`` — :class:`~robustgait.sim.feedback.FeedbackEngine` running the paper's passivity-based law
  (:class:`~robustgait.sim.passivity.PassivityController`, gains from the robot spec's ``[controller.passivity]``)
  for a flat-foot gait. A multi-contact gait keeps the joint PD in both domains — the paper's choice — on the
  rollout engine, and the engine says so (:attr:`StepEngine.controller_note`).
"""

from __future__ import annotations

from robustgait.config import SimConfig
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.sim.engine import StepEngine

MULTICONTACT_NOTE = ("the passivity-based law is for flat-foot gaits: this multi-contact gait keeps joint PD in "
                     "both domains (the paper's choice)")


def make_engine(robot: Robot, gait: Gait, config: SimConfig | None = None) -> StepEngine:
    """The engine of ``config.controller`` for this gait (module docstring). Raises a one-line
    :class:`~robustgait.errors.RobustGaitError` when the robot spec has no passivity gains."""
    config = config or SimConfig()
    if config.controller == "pd":
        return StepEngine(robot, gait, config)
    if len(gait.domains) != 1:
        engine = StepEngine(robot, gait, config)
        engine.controller_note = MULTICONTACT_NOTE
        return engine
    if robot.spec.held:
        raise RobustGaitError(f"the passivity-based law plans every joint, and {robot.name} holds "
                              f"{len(robot.spec.held)} ([joints.held]): use sim.controller pd")
    from robustgait.sim.feedback import FeedbackEngine
    from robustgait.sim.passivity import PassivityController, PassivityGains

    gains = PassivityGains.from_robot(robot)  # before building anything: a spec without gains is bad input
    return FeedbackEngine(robot, gait, PassivityController(gains), config)
