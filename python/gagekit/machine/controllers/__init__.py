"""The controller table formats, one module each: :mod:`.grid_csv` (gagekit's reference),
:mod:`.isg` (ISG kernel / Beckhoff TF5280 ``ISG_CSV``), :mod:`.fanuc` (FANUC 3-D error
compensation tape) and :mod:`.linuxcnc` (per-axis ``COMP_FILE``). Each writes its text from
the grid of :mod:`gagekit.machine.grid` and reads it back as the controller does;
:func:`gagekit.machine.export.export` chooses, writes atomically and checks the readback."""
