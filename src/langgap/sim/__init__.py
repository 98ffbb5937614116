"""The simulation: one LIBERO environment per task, its stepping, contacts and privileged state."""
