"""What a user runs to check a setup before a long run, above the engine (it runs the engine's own code; the
engine never imports it): `checks` (a check's verdict and the lines it prints as), `doctor` (`langgap doctor`:
the physics stack, renderer, assets and one environment end to end) and `policy_check` (`langgap check-policy`:
a policy through one short episode of the engine, its speed read as a run's by `policy_timing`).
"""
