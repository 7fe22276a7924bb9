from daq.cli.app import main

raise SystemExit(main())
