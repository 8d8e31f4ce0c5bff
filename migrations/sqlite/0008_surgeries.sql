-- The topological surgery (a merge or a pinch-off cut of surfaces) that made a
-- history row's state, as JSON ({"kind", "at", "components"}); NULL for the others.
ALTER TABLE history ADD COLUMN surgery TEXT;
