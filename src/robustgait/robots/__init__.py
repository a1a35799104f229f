"""Robot specs and the shipped robots (one folder each: MJCF + ``spec.toml``)."""

from robustgait.robots.spec import (
    FallCriteria,
    LegSpec,
    Robot,
    RobotSpec,
    load_robot,
    shipped_robots,
)

__all__ = ["FallCriteria", "LegSpec", "Robot", "RobotSpec", "load_robot", "shipped_robots"]
