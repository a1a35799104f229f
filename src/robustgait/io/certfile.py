"""Certificate files (``robustgait certify -o CERT.json``): the part of their schema that validation reads back
(``robustgait validate --certificate``)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Annotated, Any

import annotated_types as at

from robustgait.config import CertifyConfig, Frame, MapKind, Reconstruction
from robustgait.config.base import Bool, Doc, Float
from robustgait.errors import input_error
from robustgait.io.schema import read_json, table, validate


@table(extra="ignore")
class CertificateFile:
    """What ``validate`` needs of a certificate JSON (:meth:`robustgait.certify.GaitCertificate.to_dict`; its other
    keys are ignored): status, r*, whether the supremum is attained, x̄*, the map, frame, reconstruction and the
    certificate's config (its fixed-point search)."""

    r_star: Annotated[Float, Doc(ge=0.0)]
    attained: Bool
    x_star: Annotated[list[Float], at.MinLen(1), at.MaxLen(1000)]
    map: MapKind
    frame: Frame
    reconstruction: Reconstruction
    config: dict[str, Any] = dataclasses.field(default_factory=dict)

    def certify_config(self, src: str | Path) -> CertifyConfig:
        """The certificate's own options (a certificate of an older version: the fields it has)."""
        from robustgait.config import from_dict

        keep = {k: v for k, v in self.config.items() if k in {f.name for f in dataclasses.fields(CertifyConfig)}}
        keep.update({"map": self.map, "frame": self.frame, "reconstruction": self.reconstruction})
        return from_dict(CertifyConfig, keep, f"{src}: config", "json")


def read_certificate(path: str | Path) -> CertificateFile:
    """Read and validate a certificate JSON; one that records a failed certificate is refused (one line)."""
    raw = read_json(path, "certificate file")
    if isinstance(raw, dict) and raw.get("status", "ok") != "ok":  # a failed certificate has no ball to check
        raise input_error(path, f"the certificate has status {raw['status']!r} ({raw.get('reason', '')}): nothing "
                          "to validate against")
    return validate(raw, CertificateFile, path, "json")
