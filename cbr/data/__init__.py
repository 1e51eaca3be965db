"""Data files shipped with the CBR package (the default Action Description Database)."""
