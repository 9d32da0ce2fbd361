"""``python -m ssn_engine`` is the ``ssn-shadow`` command."""

from .cli import main

raise SystemExit(main())
