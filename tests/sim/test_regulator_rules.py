"""The step regulator's rules (robustgait.sim.regulator_rules): when it runs, its share of the H-LIP gain by the sole's
width, and the step-start blend's phase. How the regulator applies them on a robot: tests/sim/test_regulator.py."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from robustgait.config.regulator import RegulatorConfig
from robustgait.sim.regulator_rules import carry_phase, placement_share, regulator_rule


def test_the_rule_turns_the_regulator_on_for_narrow_soles_only() -> None:
    cfg = RegulatorConfig()
    assert regulator_rule(cfg, 0.12, 0.921, 1)[0] is False          # exo: 0.130
    assert regulator_rule(cfg, 0.10, 0.553, 1)[0] is False          # T1: 0.181
    on, why = regulator_rule(cfg, 0.03, 0.567, 1)                   # narrow T1: 0.053
    assert on and "0.053 < 0.1: narrow soles" in why
    assert regulator_rule(replace(cfg, mode="on"), 0.12, 0.921, 1)[0] is True
    assert regulator_rule(replace(cfg, mode="off"), 0.03, 0.567, 1)[0] is False
    assert regulator_rule(cfg, 0.03, 0.567, 2) == (False, "multi-contact gait: H-LIP step regulator off")
    with pytest.raises(ValueError, match="flat-foot gaits"):
        regulator_rule(replace(cfg, mode="on"), 0.03, 0.567, 2)


def test_the_share_of_the_hlip_gain_fades_as_the_sole_widens() -> None:
    cfg = RegulatorConfig()
    assert placement_share(cfg, 0.0, 0.5) == 1.0                                  # a point foot: the H-LIP's gain
    assert placement_share(cfg, 0.03, 0.567) == pytest.approx(1 - (0.03 / 0.567 / 0.06) ** 2)
    assert placement_share(cfg, 0.12, 0.921) == 0.0                                # exo forced on: the blend only
    assert placement_share(replace(cfg, gain_scale=0.5), 0.12, 0.921) == 0.5
    shares = [placement_share(cfg, w, 0.5) for w in np.linspace(0.0, 0.05, 11)]
    assert np.all(np.diff(shares) <= 0)


def test_the_step_start_blend_grows_with_the_share_and_stays_in_the_phase() -> None:
    """τ_c = carry_tau + carry_share κ, clipped to 1; no blend stays no blend."""
    cfg = RegulatorConfig()
    assert carry_phase(cfg, 0.0) == pytest.approx(cfg.carry_tau)
    assert carry_phase(cfg, 1.0) == pytest.approx(cfg.carry_tau + cfg.carry_share)
    assert carry_phase(replace(cfg, carry_tau=0.0), 1.0) == 0.0
    assert carry_phase(replace(cfg, carry_tau=0.9, carry_share=0.5), 1.0) == 1.0
