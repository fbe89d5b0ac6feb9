"""QIF 3.0 (ANSI/DMSC QIF 3.0, ISO 23952:2020) in and out.

- :func:`read_model` reads a model-based definition (features, datums, datum reference
  frames, characteristics; units from ``FileUnits``), :func:`part_from_model` turns it into
  a PART.toml that ``gagekit inspect`` runs, accounting for every characteristic
  (``gagekit qif import``).
- :func:`write_inspection_results` writes inspection results as a QIF
  ``MeasurementsResults`` document (``--qif-results`` on ``inspect``, ``inspect batch``).

Needs lxml (``pip install 'gagekit[qif]'``); the modules import it on first use, so
``import gagekit.qif`` works without it and the commands say which extra is missing.
"""

from __future__ import annotations

from .model import QifModel, read_model
from .results import inspection_results_document, write_inspection_results
from .to_part import PartDraft, part_from_model

__all__ = ["read_model", "QifModel", "part_from_model", "PartDraft", "write_inspection_results",
           "inspection_results_document"]
