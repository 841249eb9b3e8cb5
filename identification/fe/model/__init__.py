"""The FE model: CalculiX decks, the solver runner, the friction table and the model form.

* :mod:`.ccx` — run a deck in its own temporary folder (time-out, OMP_NUM_THREADS=1), detect
  a failed or unconverged run, parse the ``.dat`` prints, cache by deck hash.
* :mod:`.deck` — what every deck shares: the sector factor, ``*PLASTIC`` and ``*STATIC`` lines.
* :mod:`.upsetting` — axisymmetric upsetting half model (O-grid core, boundary layer at the rim
  corner, meshed rigid platen, surface-to-surface Coulomb contact; docs/calculix.md "Upsetting").
* :mod:`.tension` — tension with necking, CAX8R quarter model (docs/calculix.md "Tension").
* :mod:`.realised_law` — the ``*PLASTIC`` rows CalculiX realises as a given law.
* :mod:`.table` — the FE friction table (bulge and force factor vs μ, h0/d0, strain, n)
  shipped as package data and made by :mod:`..make_table`.
* :mod:`.model_form` — what another defensible model puts elsewhere (the model form's share).

This package imports nothing of flowcurve.identification outside it: the corrections that use
the table (friction, compression) sit above it, the inverse FE and verification (``fe``) above those.
"""
