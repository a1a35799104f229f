"""Shared fixtures: the shipped ``exo`` robot with a gait made by the package (tests/data/exo_gait.json, the
default ``robustgait gait generate --robot exo`` gait), and the Atalante model and FROST gait from
../shared/atalante (read, never copied; tests that need it are skipped with the reason when it is absent)."""

from __future__ import annotations

import os
from pathlib import Path

# MuJoCo picks its GL backend once, at import: make offscreen rendering headless before any test imports it.
os.environ.setdefault("MUJOCO_GL", "egl")

import pytest

REPO = Path(__file__).resolve().parents[1]
ATALANTE_DIR = REPO.parent / "shared" / "atalante"
ATALANTE_SPEC = REPO / "examples" / "atalante.toml"
ATALANTE_GAIT = ATALANTE_DIR / "jt_bez_2023-09-10.yaml"
EXO_GAIT = REPO / "tests" / "data" / "exo_gait.json"

needs_atalante = pytest.mark.skipif(not (ATALANTE_DIR / "loadedExo.xml").is_file(),
                                    reason="../shared/atalante (AMBER lab model) is not beside the repository")


@pytest.fixture(scope="session")
def atalante():  # type: ignore[no-untyped-def]
    if not (ATALANTE_DIR / "loadedExo.xml").is_file():
        pytest.skip("../shared/atalante is not beside the repository")
    from robustgait import load_robot

    return load_robot(ATALANTE_SPEC)


@pytest.fixture(scope="session")
def atalante_gait(atalante):  # type: ignore[no-untyped-def]
    from robustgait import load_gait

    return load_gait(ATALANTE_GAIT, atalante)


@pytest.fixture(scope="session")
def exo():  # type: ignore[no-untyped-def]
    from robustgait import load_robot

    return load_robot("exo")


@pytest.fixture(scope="session")
def exo_gait(exo):  # type: ignore[no-untyped-def]
    from robustgait import load_gait

    return load_gait(EXO_GAIT, exo)


@pytest.fixture(scope="session", params=["exo", "atalante"])
def robot_gait(request):  # type: ignore[no-untyped-def]
    """(robot, gait) for the shipped exo with its stored gait, and for Atalante with its FROST gait."""
    if request.param == "exo":
        return request.getfixturevalue("exo"), request.getfixturevalue("exo_gait")
    return request.getfixturevalue("atalante"), request.getfixturevalue("atalante_gait")
