"""The HTML report of a run (``report.html``): :func:`write_report`, :func:`build_html`; the
surfaces of its 3D view: :func:`write_surfaces` (written by the run)."""

from fenics_garment.report.page import REPORT_FILE, ReportError, build_html, write_report
from fenics_garment.report.surfaces import SURFACES_FILE, Surface, write_surfaces

__all__ = ["REPORT_FILE", "SURFACES_FILE", "ReportError", "Surface", "build_html",
           "write_report", "write_surfaces"]  # fmt: skip
