from eulertop.cli import main

raise SystemExit(main())
