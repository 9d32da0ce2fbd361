"""The GIMP 3 plug-in of ssn-shadow: the plug-in folder ``ssn-shadow/`` and its installer."""
