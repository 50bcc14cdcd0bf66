-- Rows of the runs table: simulations started, ever.
-- no parameters
SELECT count(*) FROM runs
