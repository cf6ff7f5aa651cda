"""eulertop reference solver: every result R1–R21 of ../shared/physics.md, vectorised."""
