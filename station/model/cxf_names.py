"""Names of the CxF3 colour exchange format (ISO 17972-1) that every CxF3 reader and writer shares.

The library and design writer (``station.formulate.cxf``) and the measurement importer and exporter
(``station.ingest.formats.cxf``) both speak CxF3-core; its namespace and the creator string this
product writes are defined here once.
"""

from __future__ import annotations

#: XML namespace of CxF3-core documents.
NAMESPACE = "http://colorexchangeformat.com/CxF3-core"
#: ``<FileInformation><Creator>`` of every CxF3 file the station writes.
CREATOR = "CACAD Station"
