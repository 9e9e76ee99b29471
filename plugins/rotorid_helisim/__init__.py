"""The ``helisim`` data source: a nonlinear Bo-105-class truth model flown through the
identification and verification maneuvers (see docs/maneuvers.md)."""
