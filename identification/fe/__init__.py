"""CalculiX (ccx) in the loop: inverse FE identification and verification, above the FE model.

* :mod:`.model` — the FE model (decks, solver runner, friction table, model form); it imports
  nothing of the identification, which may use it.
* :mod:`.inverse`, :mod:`.inverse_tension` — the inverse FE of compression and of tension
  (:func:`flowcurve.identification.identify.identify_inverse_fe` chooses between them);
  :mod:`.law_choice` the law both fit when none is given; :mod:`.solver_fit` their least squares.
* :mod:`.verify` — the identified curve run through the model against the record.
* :mod:`.make_table`, :mod:`.make_tension_response`, :mod:`.synthetic` — tables and records made
  with the model.
"""
