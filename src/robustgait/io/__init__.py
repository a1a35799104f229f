"""Everything robustgait reads and writes, validated in one place (issue 11; ``docs/inputs.md``).

* :mod:`robustgait.io.limits` — the documented limits of every input (files and command-line arguments).
* :mod:`robustgait.io.schema` — reading files safely (size, encoding, syntax) and validating their data
  against msgspec schemas; errors read ``FILE: field: problem`` on one line.
* :mod:`robustgait.io.gaitfile`, :mod:`robustgait.io.specfile`, :mod:`robustgait.io.logs` — the schemas
  and builders of gait files (JSON, FROST YAML), robot specs (TOML) and reduced-state logs (CSV, NPY, NPZ).
* :mod:`robustgait.io.output` — the one output writer: checks a target before any work, writes atomically.
* :mod:`robustgait.io.args` — argparse types with the documented bounds, for the command line.

The public dataclasses (:class:`~robustgait.gait.Gait`, :class:`~robustgait.robots.RobotSpec`, ...) stay
where they are; this package validates raw data and builds them. Submodules are imported on demand.
"""
