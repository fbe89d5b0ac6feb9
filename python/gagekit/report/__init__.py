"""Reports: self-contained HTML with tables and matplotlib figures (PNG, embedded).

One module serves the demo and every ``--report DIR`` option of the CLI.
"""

from .html import Report

__all__ = ["Report"]
