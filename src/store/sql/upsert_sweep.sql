-- Registers a sweep, or updates the one of this name; returns its id.
-- ?1: name, ?2: file path, ?3: source text, ?4: description, ?5: cost, ?6: axes (JSON),
-- ?7: replicas, ?8: now (created at / updated at)
INSERT INTO sweeps (name, file, source, description, cost, axes, replicas,
    created_at, updated_at)
VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?8)
ON CONFLICT (name) DO UPDATE SET file = ?2, source = ?3, description = ?4,
    cost = ?5, axes = ?6, replicas = ?7, updated_at = ?8
RETURNING id
