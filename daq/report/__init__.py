"""The report of one run: PNG figures (figures.py) and one self-contained HTML page
(page.py) that opens from disk with no network."""
