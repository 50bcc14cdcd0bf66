-- The file text a sweep was last registered with, by name.
-- ?1: sweep name
SELECT source FROM sweeps WHERE name = ?1
