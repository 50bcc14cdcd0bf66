-- The file text a sweep was last registered with.
-- ?1: sweep id
SELECT source FROM sweeps WHERE id = ?1
