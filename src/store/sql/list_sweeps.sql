-- All sweeps, oldest first.
-- no parameters
SELECT id, name, file, description, cost, axes, replicas, created_at,
updated_at, left_out FROM sweeps ORDER BY id
