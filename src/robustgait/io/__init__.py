"""Everything robustgait reads and writes, validated in one place (``docs/inputs.md``): no other module opens a file.

* :mod:`robustgait.io.schema` — reading files safely (size, encoding, syntax) and validating their data with the
  configuration's schema library (pydantic); errors read ``FILE: field: problem`` on one line.
* :mod:`robustgait.io.limits` — the limits of every input file.
* :mod:`robustgait.io.gaitfile`, :mod:`robustgait.io.robotfile`, :mod:`robustgait.io.logs`,
  :mod:`robustgait.io.certfile`, :mod:`robustgait.io.configfile` — gait files (JSON, FROST YAML), robots (spec
  TOML, MJCF), reduced-state logs (CSV, NPY, NPZ), certificate files, configuration files (TOML).
* :mod:`robustgait.io.output` — the one output writer: checks a target before any work, writes atomically.

The data they build (:class:`~robustgait.gait.Gait`, :class:`~robustgait.robots.RobotSpec`, the configuration) is
plain data defined elsewhere. Submodules are imported on demand.
"""
