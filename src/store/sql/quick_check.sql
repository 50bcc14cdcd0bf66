-- SQLite's quick integrity check of an existing wetgran database.
-- no parameters
PRAGMA quick_check
