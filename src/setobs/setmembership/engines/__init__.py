"""The SMFDO's engines, one per file: each answers a step (an ``Outcome``), hands it off
to the reference engine (a ``Handoff``) or declines (``None``); :class:`setobs.SMFDO`
runs them in order and is the only dispatcher."""
