"""eulertop reference solver: every result R1–R21 of the physics page (docs/physics/index.md),
vectorised."""
