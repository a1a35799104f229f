"""The certificate of a gait, one package (``docs/certificate.md``): the orbit the gait walks (:mod:`.orbit`: the
band of its switching states, its period, whether perturbed states come back; :func:`find_orbit`, the one way in, over
a gait walked here, a walk the caller already has or a map: :class:`Walking`, :class:`Walked`, :class:`Iterated`), the
maps on the switching surface (:mod:`.returnmap`: full states; :mod:`.reduced`: the certificate's reduced state), the
barrier and its estimators (:mod:`.barrier`, :mod:`.estimators`, :mod:`.shape`), the push map (:mod:`.push`), recovery
to the orbit's band (:mod:`.band`), and :func:`certify_gait`, which puts them together. Maps with known answers:
:mod:`.synthetic`.
"""

from typing import TYPE_CHECKING, Any

from robustgait._lazy import lazy_exports

if TYPE_CHECKING:
    from robustgait.certificate.barrier import Certificate, certify_map, invariant_radius
    from robustgait.certificate.certify import GaitCertificate, certify_gait
    from robustgait.certificate.estimators import certify_map_sequential
    from robustgait.certificate.search import Iterated, Walked, Walking, find_orbit

_EXPORTS = {
    **dict.fromkeys(("Certificate", "certify_map", "invariant_radius"), "barrier"),
    **dict.fromkeys(("GaitCertificate", "certify_gait"), "certify"),
    "certify_map_sequential": "estimators",
    **dict.fromkeys(("Iterated", "Walked", "Walking", "find_orbit"), "search"),
}

_getattr = lazy_exports(__name__, _EXPORTS)


def __getattr__(name: str) -> Any:
    return _getattr(name)


__all__ = ["Certificate", "GaitCertificate", "Iterated", "Walked", "Walking", "certify_gait", "certify_map",
           "certify_map_sequential", "find_orbit", "invariant_radius"]
