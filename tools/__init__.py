"""Developer commands that are neither the package, its tests nor a benchmark (run from the repository root)."""
