from flowcurve.cli import main

raise SystemExit(main())
