"""``python -m harness.archive``: list, summarize and export run archives (``cli``)."""

from harness.archive.cli import main

raise SystemExit(main())
