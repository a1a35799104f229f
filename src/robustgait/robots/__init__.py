"""Robot specs and the shipped robots (one folder each: MJCF + ``spec.toml``)."""

from robustgait.robots.spec import (
    FallCriteria,
    GaitQuality,
    LegSpec,
    ParamRange,
    Robot,
    RobotSpec,
    load_robot,
    shipped_robots,
)

__all__ = ["FallCriteria", "GaitQuality", "LegSpec", "ParamRange", "Robot", "RobotSpec", "load_robot", "shipped_robots"]
