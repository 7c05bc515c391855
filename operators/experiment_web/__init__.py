"""The 2AFC experiment's web app (paper section 6.2): the server ``experiment-serve`` starts
(``server.py``) and the page it serves (``page/``)."""
