"""axialdeform.three: the npm module axialdeform-three (ES modules, type declarations), shipped in
the wheel for the web page and the notebook widget; read with importlib.resources
(:func:`axialdeform.web.module_source`).  Not Python code: this file only makes the folder a package."""
