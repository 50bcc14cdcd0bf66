-- SQLite's full integrity check (every page, index and constraint); one row `ok` when sound.
-- no parameters
PRAGMA integrity_check
