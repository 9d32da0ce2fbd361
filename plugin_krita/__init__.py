"""The Krita plug-in of ssn-shadow: the ``ssn_shadow`` pykrita package and its installer."""
