-- Grid points a sweep file's `skip_invalid` left out, with the scene constraint they fail
-- (JSON: [{coords, constraint, reason}]); shown by `sweep status`. NULL: none, or registered
-- before this column existed.
ALTER TABLE sweeps ADD COLUMN left_out TEXT;
