"""``python -m ground.archive``: list, summarize and export run archives (``cli``)."""

from ground.archive.cli import main

raise SystemExit(main())
