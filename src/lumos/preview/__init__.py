"""The live preview: `lumos serve SCENE` and `lumos render ... --preview` (docs/preview.md).

`session` holds the scene, edits it and renders it progressively in a thread (no web code); `server` serves the
page (`static/`) and speaks to it over a WebSocket (Starlette and uvicorn: `pip install "lumos[preview]"`).
Importing this package imports neither.
"""
