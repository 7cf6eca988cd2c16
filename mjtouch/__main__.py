from mjtouch.cli import main

raise SystemExit(main())
