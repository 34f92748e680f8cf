/* A workbench session that ended (expired, its token revoked) while a page was open: the next request of
the page is answered 401; go to the sign-in page, which brings the user back here afterwards (ui: the
server's auth check, shimmy/service/auth.py). */
(function () {
    const original = window.fetch;
    if (!original) { return; }
    window.fetch = function () {
        return original.apply(this, arguments).then(function (response) {
            if (response.status === 401 && !window.location.pathname.endsWith("/login")) {
                const here = window.location.pathname + window.location.search;
                window.location.assign("/login?next=" + encodeURIComponent(here));
            }
            return response;
        });
    };
})();
