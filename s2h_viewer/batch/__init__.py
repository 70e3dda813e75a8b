"""Batch retargeting of a motion library onto a cast of avatars (`s2h batch`) on Dask distributed.

`plan` (what to do and where it goes), `task` (one retarget in any process), `cluster` (Dask: the only
importer of it in the project), `runner` (progress, skipping finished work), `summary` (CSV) and `report`
(the HTML page)."""
