"""The papers' systems (and our own demonstration system), as plain data and functions."""
