"""Report: a day of cleat runs in one folder.

* :mod:`~identification.report.batch` - the whole chain over many recordings (local pool or Dask);
* :mod:`~identification.report.tables` - the report's tables, as HTML rows and as CSV;
* :mod:`~identification.report.campaign` - repeated runs of a condition pooled into one k, c per tire;
* :mod:`~identification.report.plots` - the figures (matplotlib, headless);
* :mod:`~identification.report.html` - the self-contained HTML report.
"""
