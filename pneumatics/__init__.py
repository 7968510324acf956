"""pneumatics"""
