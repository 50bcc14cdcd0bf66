-- Opens a write transaction, taking the write lock at once.
-- no parameters
BEGIN IMMEDIATE
