"""The Solent study (see :mod:`.scene`)."""
