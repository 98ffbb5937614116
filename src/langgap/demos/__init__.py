"""Scripted demonstrations: collected with the oracle from fresh placements, stored compactly, exported (LeRobot, HDF5).

A demonstration never starts from an evaluation init state: each attempt resets with LIBERO's own
placement samplers (objects and fixtures drawn from the BDDL regions) seeded with `seed + attempt`,
and the start is checked against the task's 50 fixed init states. Attempt `j` uses the same seed for
every task, so the tasks of one scene are demonstrated from identical placements, as in the benchmark.
"""
