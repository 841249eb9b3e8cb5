"""CalculiX (ccx) in the product: deck writers, a runner with a cache, and FE friction tables.

* :mod:`.ccx` — run a deck in its own temporary folder (time-out, OMP_NUM_THREADS=1), detect
  a failed or unconverged run, parse the ``.dat`` prints, cache by deck hash.
* :mod:`.upsetting` — axisymmetric upsetting half model (O-grid core, boundary layer at the rim
  corner, meshed rigid platen, surface-to-surface Coulomb contact; docs/calculix.md "Upsetting").
* :mod:`.tension` — tension with necking, CAX8R quarter model (docs/calculix.md "Tension").
* :mod:`.table` — the FE friction table (bulge and force factor vs μ, h0/d0, strain, n)
  shipped as package data and made by :mod:`.make_table`.
"""
