"""``motionlang serve``: a local web app over :mod:`motionlang.api`.

The layer above ``api``: :mod:`.options` (the server's options, torch-free for ``--help``),
:mod:`.studio` (what the page asks for, as Python: models loaded once, generated takes,
uploaded rigs, descriptions, searches, exports), :mod:`.uploads` (uploaded files read with
the CLI's limits), :mod:`.views` (motions as the JSON the viewer draws) and :mod:`.app` (the
FastAPI routes and the server). The page and its canvas viewer are plain files in
``static/``, served from the package: nothing is fetched from elsewhere.
"""
