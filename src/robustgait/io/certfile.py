"""Certificate files (``robustgait certify -o CERT.json``): the part of their schema that validation reads back
(``robustgait validate --certificate``), and the certified figure of a certificate record (``value``, with
``estimate`` and ``verified``; files written before the figure had one name hold it as ``j_star`` of a push
certificate or ``r_star``)."""

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
    state, set, horizon and fixed-point search). The figure is ``value`` (``verified``; an exploration alone: its
    ``estimate``); older files name it ``j_star`` or ``r_star``."""

    attained: Bool
    x_star: Annotated[list[Float], at.MinLen(1), at.MaxLen(1000)]
    map: MapKind
    frame: Frame
    reconstruction: Reconstruction
    config: dict[str, Any] = dataclasses.field(default_factory=dict)
    coordinates: dict[str, Any] | None = None
    energy: Annotated[Float, Doc(ge=0.0)] | None = None
    value: Annotated[Float, Doc(ge=0.0)] | None = None
    estimate: Annotated[Float, Doc(ge=0.0)] | None = None
    verified: Bool = True

    @property
    def radius(self) -> float:
        """The certificate's radius (:func:`certificate_radius`; :func:`read_certificate` refuses a file without)."""
        return certificate_radius({"value": self.value, "estimate": self.estimate, "verified": self.verified})

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


LEGACY_FIGURE_KEYS = ("j_star", "r_star")  # a certificate file's figure before it was named value (push: j_star)


def read_certificate(path: str | Path) -> CertificateFile:
    """Read and validate a certificate JSON; one that records a failed certificate is refused (one line)."""
    raw = read_json(path, "certificate file")
    if isinstance(raw, dict) and raw.get("status", "ok") != "ok":  # a failed certificate has no ball to check
        raise input_error(path, f"the certificate has status {raw['status']!r} ({raw.get('reason', '')}): nothing "
                          "to validate against")
    if isinstance(raw, dict) and raw.get("value") is None:  # written before the figure was named value
        old = next((raw[k] for k in LEGACY_FIGURE_KEYS if raw.get(k) is not None), None)
        raw = {k: v for k, v in raw.items() if k not in LEGACY_FIGURE_KEYS} | {"value": old}
    out = validate(raw, CertificateFile, path, "json")
    if out.value is None:
        raise input_error(path, "the certificate has no figure (value)")
    return out


def certificate_radius(record: Mapping[str, Any]) -> float:
    """The radius of a certificate record (:meth:`~robustgait.certificate.certify.GaitCertificate.to_dict`, a file or
    a study's copy): its ``value`` when ``verified``, else its ``estimate`` (an exploration alone); a record written
    before the figure was named ``value``: ``j_star`` (push), else ``r_star`` (None counts as absent). KeyError when
    it has none."""
    for key in LEGACY_FIGURE_KEYS:
        if record.get(key) is not None and record.get("value") is None:
            return float(record[key])
    if not record.get("verified", True) and record.get("estimate") is not None:
        return float(record["estimate"])
    return float(record["value"])


def certificate_value(record: Mapping[str, Any]) -> float:
    """The certified figure of a certificate record (0 unless verified; files of every version, as
    :func:`certificate_radius`)."""
    return certificate_radius(record) if record.get("verified", True) else 0.0
