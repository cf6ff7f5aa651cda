from eulertop.cli import script

raise SystemExit(script())
