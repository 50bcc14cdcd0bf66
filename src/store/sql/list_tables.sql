-- Tables of a database that is SQLite but not (yet) wetgran's.
-- no parameters
SELECT name FROM sqlite_master WHERE type = 'table' ORDER BY name
