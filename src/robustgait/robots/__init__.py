"""Robots: their specs as data (:mod:`robustgait.robots.spec`), the compiled robot (:mod:`robustgait.robots.model`),
its soles and floor as MuJoCo collides them (:mod:`robustgait.robots.soles`; the sole box every part reads,
:mod:`robustgait.robots.solebox`) and the shipped robots (one folder each: MJCF + ``spec.toml``, read by
:func:`robustgait.io.robotfile.load_robot`)."""

from robustgait.robots.model import Robot
from robustgait.robots.spec import FallCriteria, GaitQuality, LegSpec, ParamRange, RobotSpec

__all__ = ["FallCriteria", "GaitQuality", "LegSpec", "ParamRange", "Robot", "RobotSpec"]
