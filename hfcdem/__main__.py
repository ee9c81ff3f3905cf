"""Allow ``python3 -m hfcdem``."""

from hfcdem.cli import main

raise SystemExit(main())
