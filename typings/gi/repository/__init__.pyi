"""GObject-introspection namespaces: generated at run time from GIMP's typelibs, so each is an untyped module."""
