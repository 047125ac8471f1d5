"""Contact laws: one contact in, forces out (scalars only; STYLE.md §5 rule 3)."""
