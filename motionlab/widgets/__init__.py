"""Interactive widgets of the chapters, one module per chapter.

Each widget's callback is a plain function (unit-tested without a browser); the ipywidgets wiring around it
is a thin layer that notebooks display.
"""
