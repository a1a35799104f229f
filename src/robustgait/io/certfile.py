"""Certificate files (``robustgait certify -o CERT.json``): the part of their schema that validation reads back
(``robustgait validate --certificate``), and the certified figure of a certificate record (``j_star`` of a push
certificate, ``r_star`` of a state certificate; older push certificates wrote ``r_star``)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any

import annotated_types as at

from robustgait.config import CertifyConfig, Frame, MapKind, Reconstruction
from robustgait.config.base import Bool, Doc, Float
from robustgait.errors import input_error
from robustgait.io.schema import read_json, table, validate


@table(extra="ignore")
class CertificateFile:
    """What ``validate`` needs of a certificate JSON (:meth:`robustgait.certificate.certify.GaitCertificate.to_dict`;
    its other keys are ignored): status, r*, whether the supremum is attained, z* (the centre in the certificate's
    coordinates), the map, frame, reconstruction, the coordinates' transform T (z = T x̄; absent in certificates of the
    base angular velocity written before states were a choice: the identity), E* and the certificate's config (its
    state, set, horizon and fixed-point search)."""

    attained: Bool
    x_star: Annotated[list[Float], at.MinLen(1), at.MaxLen(1000)]
    map: MapKind
    frame: Frame
    reconstruction: Reconstruction
    config: dict[str, Any] = dataclasses.field(default_factory=dict)
    coordinates: dict[str, Any] | None = None
    energy: Annotated[Float, Doc(ge=0.0)] | None = None
    r_star: Annotated[Float, Doc(ge=0.0)] | None = None  # a state certificate's r* (a push certificate's J*, before
    j_star: Annotated[Float, Doc(ge=0.0)] | None = None  # its figure was named j_star)

    @property
    def value(self) -> float:
        """The certified figure: ``j_star`` of a push certificate, else ``r_star`` (0 when neither is written:
        :func:`read_certificate` refuses such a file)."""
        return certificate_figure({"j_star": self.j_star, "r_star": self.r_star or 0.0})

    def transform(self, src: str | Path) -> list[list[float]] | None:
        """T (k, k) of the certificate's coordinates, checked square of the size of x*; None if absent."""
        t = (self.coordinates or {}).get("transform")
        if t is None:
            return None
        k = len(self.x_star)
        if (not isinstance(t, list) or len(t) != k
                or not all(isinstance(r, list) and len(r) == k and all(isinstance(v, (int, float)) and
                                                                       not isinstance(v, bool) and math.isfinite(v)
                                                                       for v in r) for r in t)):
            raise input_error(src, f"coordinates.transform must be a {k} × {k} matrix of finite numbers")
        return [[float(v) for v in r] for r in t]

    def certify_config(self, src: str | Path) -> CertifyConfig:
        """The certificate's own options (a certificate of an older version: the fields it has; one written before
        states were a choice certified the base angular velocity in a ball, one step; the fields of a fixed-point search
        that the orbit search replaced are dropped, :func:`~robustgait.config.certify.without_retired`)."""
        from robustgait.config import STATE_CHOICE_DEFAULTS, from_dict
        from robustgait.config.certify import without_retired

        fields = {f.name for f in dataclasses.fields(CertifyConfig)}
        keep = {k: v for k, v in without_retired(self.config).items() if k in fields}
        for k, v in {**STATE_CHOICE_DEFAULTS, "disturbance": "state"}.items():
            keep.setdefault(k, v)
        keep.update({"map": self.map, "frame": self.frame, "reconstruction": self.reconstruction})
        if keep["disturbance"] == "push":  # written before the two were exclusive, it may carry an unused choice
            keep.update(STATE_CHOICE_DEFAULTS)
        cfg = from_dict(CertifyConfig, keep, f"{src}: config", "json")
        want = 2 if cfg.disturbance == "push" else {"omega": 3, "centroidal": 6}.get(cfg.state)
        if want is not None and len(self.x_star) != want:
            raise input_error(src, f"x_star has {len(self.x_star)} values, a {cfg.space} certificate has {want}")
        return cfg


def read_certificate(path: str | Path) -> CertificateFile:
    """Read and validate a certificate JSON; one that records a failed certificate is refused (one line)."""
    raw = read_json(path, "certificate file")
    if isinstance(raw, dict) and raw.get("status", "ok") != "ok":  # a failed certificate has no ball to check
        raise input_error(path, f"the certificate has status {raw['status']!r} ({raw.get('reason', '')}): nothing "
                          "to validate against")
    out = validate(raw, CertificateFile, path, "json")
    if out.j_star is None and out.r_star is None:
        raise input_error(path, "the certificate has no figure (j_star or r_star)")
    return out


def certificate_figure(record: Mapping[str, Any]) -> float:
    """The certified figure of a certificate record (:meth:`~robustgait.certificate.certify.GaitCertificate.to_dict`,
    a file or a study's copy): ``j_star`` of a push certificate, ``r_star`` of a state certificate or of a push
    certificate written before its figure was named (a ``j_star`` of None counts as absent). KeyError when it has
    neither."""
    j_star = record.get("j_star")
    return float(j_star if j_star is not None else record["r_star"])
