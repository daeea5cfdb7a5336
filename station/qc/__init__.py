"""Colour QC of samples against standards: jobs, standards, repeats, checks, metamerism, reports.

The stable entry points other fronts (``station qc …``, the service's ``/api/v1/qc`` routes, the
viewer's QC screen) call; each takes plain values or a SQLAlchemy session and returns a frozen
dataclass with ``to_dict()``:

=============================================  =============================================================
:func:`station.qc.readings.load_readings`      readings of a ``station measure --json`` / ``import --json`` file
:func:`station.qc.readings.reading_from_dict`  one reading from such a JSON object
:func:`station.qc.check.check_pair`            verdict of a sample against its standard → ``QcVerdict``
:func:`station.qc.repeats.summarise`           mean, sd per geometry and outliers of N readings
:func:`station.qc.repeats.correlate`           bias of instrument B against A on a shared panel
:func:`station.qc.metamerism.metamerism`       metamerism index D65 → A, F11 per geometry
:func:`station.qc.jobs.search_measurements`    measurements by job, part, instrument, time range
:func:`station.qc.jobs.list_jobs`              jobs with their parts and counts
:func:`station.qc.jobs.set_standard`           a measurement or design as the standard of a job and part
:func:`station.qc.jobs.job_summary`            every part's standard and every sample's verdict
:func:`station.qc.spc.control_limits`          individuals-chart centre and ± 3σ limits of ΔE over time
:func:`station.qc.report.write_pdf`            the job's QC report as PDF (``write_csv``, ``write_trend_png``)
=============================================  =============================================================

The science (ΔE formulas, tolerance sets, verdict rules) lives in :mod:`station.qc.tolerance` and
:mod:`station.model.difference`; this package applies it to readings and stored jobs.
"""
