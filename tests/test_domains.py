import numpy as np
import pytest

from robustgait import RobustGaitError
from robustgait.domains import FLAT, MULTICONTACT, Contact, domain_graph
from robustgait.dynamics import Dynamics, impact_map, impact_residual
from robustgait.gaitgen.problem import double_support_free_joints


def test_graphs_and_their_transitions():
    assert domain_graph("flat") is FLAT and domain_graph("multicontact") is MULTICONTACT
    with pytest.raises(RobustGaitError, match="unknown domain graph"):
        domain_graph("hopping")
    # flat: the swing sole lands flat and becomes the next step's stance
    assert FLAT.target_contacts(0) == (Contact("swing", "flat"),)
    # multi-contact: heel strike onto (stance toe line, swing heel line); foot-flat onto the swing sole, relabeled
    ss, ds = MULTICONTACT.domains
    assert ss.guard == "touchdown" and ds.guard == "foot_flat"
    assert MULTICONTACT.target_contacts(0) == ds.contacts == (Contact("stance", "toe"), Contact("swing", "heel"))
    assert MULTICONTACT.target_contacts(1) == (Contact("swing", "flat"),)
    # a flat sole fixes 6 rows, a line 5 (pitch about the line is free)
    assert Contact("stance", "flat").n_rows == 6 and Contact("swing", "heel").rows == (0, 1, 2, 3, 5)
    assert Contact("swing", "toe").side("right") == "left" and Contact("stance", "heel").frame_kind() == "heel"


def test_impact_map_solves_the_kkt_system():
    """[M −Jᵀ; J 0][q̇⁺; Λ] = [M q̇⁻; 0]: the solve's output zeroes both residual blocks (NumPy form)."""
    rng = np.random.default_rng(0)
    a = rng.normal(size=(8, 8))
    M = a @ a.T + 8 * np.eye(8)
    J = rng.normal(size=(3, 8))
    v = rng.normal(size=8)
    vp, lam = impact_map(M, J, v)
    momentum, contact = impact_residual(M, J, v, vp, lam)
    np.testing.assert_allclose(momentum, 0, atol=1e-12)
    np.testing.assert_allclose(contact, 0, atol=1e-12)
    # plastic impact: kinetic energy is lost, never gained
    assert vp @ M @ vp <= v @ M @ v


def test_line_contact_impact_on_exo(exo, exo_mc_gait):
    """Heel strike of the multi-contact gait: after the impact both line contacts are still (J q̇⁺ = 0) and
    the momentum jump is their impulses (M Δq̇ = Jᵀ Λ), with MuJoCo's own M."""
    import mujoco

    dyn = Dynamics(exo)
    s = exo_mc_gait.pre_impact_state
    contacts = MULTICONTACT.target_contacts(0)
    plus, lam = dyn.impact_map(s.qpos, s.qvel, contacts, exo_mc_gait.stance)
    J = dyn.contact_jacobian(s.qpos, contacts, exo_mc_gait.stance)
    assert J.shape == (10, exo.model.nv) and lam.shape == (10,)
    np.testing.assert_allclose(J @ plus, 0, atol=1e-10)
    d = mujoco.MjData(exo.model)
    d.qpos[:] = s.qpos
    mujoco.mj_forward(exo.model, d)
    M = np.zeros((exo.model.nv, exo.model.nv))
    mujoco.mj_fullM(exo.model, d, M)
    np.testing.assert_allclose(M @ (plus - s.qvel), J.T @ lam, atol=1e-8)
    assert lam[2] >= -1e-9 and lam[7] >= -1e-9  # both lines push


def test_double_support_free_joints(exo):
    # the front (left) leg's hip roll, hip yaw, knee and ankle roll, picked from the joint axes
    free = double_support_free_joints(exo, "left")
    assert [exo.spec.joints[j] for j in free] == ["left_hip_roll", "left_hip_yaw", "left_knee", "left_ankle_roll"]
    assert [exo.spec.joints[j] for j in double_support_free_joints(exo, "right")][2] == "right_knee"
    names = ("left_hip_roll", "left_hip_yaw", "left_knee", "left_ankle_pitch")
    assert double_support_free_joints(exo, "left", names) == [0, 1, 3, 4]
    with pytest.raises(RobustGaitError, match="4 actuated joints"):
        double_support_free_joints(exo, "left", ("left_knee",))
