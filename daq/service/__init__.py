"""The lab service (``daq serve``): one process owns the analyzer, runs captures on
request, analyses every run as it lands, and serves an HTTP API and a live web page.
docs/service.md describes it."""
