"""Known defects of the stated uncertainty: (kind, quantity) → what misses, measured."""

KNOWN: dict[tuple[str, str], str] = {}
