import http.server, sys, os
out = sys.argv[2]
class H(http.server.SimpleHTTPRequestHandler):
    extensions_map = {**http.server.SimpleHTTPRequestHandler.extensions_map, '.wasm': 'application/wasm', '.js': 'text/javascript'}
    def do_POST(self):
        n = int(self.headers.get('Content-Length', 0)); body = self.rfile.read(n)
        # Only a bare file name (frame, error): nothing outside the output directory.
        name = os.path.basename(self.path.split('?')[0]) or 'post'
        open(os.path.join(out, name), 'wb').write(body)
        self.send_response(200); self.end_headers()
    def log_message(self, *a): pass
os.chdir(os.path.dirname(os.path.abspath(__file__)))
http.server.ThreadingHTTPServer(('127.0.0.1', int(sys.argv[1])), H).serve_forever()
