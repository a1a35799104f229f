import robustgait


def test_public_api_exports():
    for name in robustgait.__all__:
        assert getattr(robustgait, name) is not None
    from robustgait.certificate.barrier import certify_map, invariant_radius

    assert robustgait.invariant_radius is invariant_radius and robustgait.certify_map is certify_map
    assert robustgait.GaitGenerator.__module__ == "robustgait.gaitgen.solve"
